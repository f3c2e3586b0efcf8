// Test hook of the shadow toggle (window.pointdagViewer.shadowProbe): where some drawn voxels of
// shaded tiles land on screen, with their light, so a test can compare those pixels with the shading
// on and off. Voxels are taken at an even stride over the drawn tiles, `limit` at most.
import * as THREE from 'three';

// drawn: [{points, voxels}] (TileNodes, or the 3D Tiles view's stand-ins).
// -> [{x, y, light}]: CSS pixels of the canvas (voxel centres in front of the camera and on screen).
export function probeVoxelLight(drawn, view, limit) {
  const tiles = drawn.filter((n) => n.points?.userData.shadow === 'shaded');
  const total = tiles.reduce((sum, n) => sum + n.voxels, 0);
  const stride = Math.max(1, Math.ceil(total / limit));
  const width = view.container.clientWidth;
  const height = view.container.clientHeight;
  view.camera.updateMatrixWorld();
  const p = new THREE.Vector3();
  const found = [];
  for (const node of tiles) {
    const { position, shadowLight } = node.points.geometry.attributes;
    for (let i = 0; i < node.voxels; i += stride) {
      p.fromBufferAttribute(position, i).applyMatrix4(node.points.matrixWorld).project(view.camera);
      if (Math.abs(p.x) > 1 || Math.abs(p.y) > 1 || Math.abs(p.z) > 1) continue;
      found.push({ x: ((p.x + 1) / 2) * width, y: ((1 - p.y) / 2) * height, light: shadowLight.array[i] });
    }
  }
  return found;
}
