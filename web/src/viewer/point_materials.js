// One PointsMaterial per level (and per color/no color): square points as wide as the level's voxel.
// three's size attenuation scales by (drawing-buffer height / 2) / depth, which misses the
// projection's 1 / tan(fov / 2): dividing by it makes `size` a true length in world units.
import * as THREE from 'three';

const NO_COLOR = 0xc8ccd4; // scans without color

// The `size` of a size-attenuated PointsMaterial whose points are `voxelSize` wide in world units.
export function worldPointSize(voxelSize, camera) {
  return voxelSize / Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
}

export class PointMaterials {
  constructor(camera) {
    this.camera = camera;
    this.materials = new Map();
  }

  get(voxelSize, hasColor) {
    const key = `${voxelSize}/${hasColor}`;
    let material = this.materials.get(key);
    if (!material) {
      material = new THREE.PointsMaterial({
        size: worldPointSize(voxelSize, this.camera),
        sizeAttenuation: true,
        vertexColors: hasColor,
        color: hasColor ? 0xffffff : NO_COLOR,
      });
      this.materials.set(key, material);
    }
    return material;
  }

  dispose() {
    for (const m of this.materials.values()) m.dispose();
    this.materials.clear();
  }
}
