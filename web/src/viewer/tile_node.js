// One tile (l, x, y, z) of a dataset (PROTOCOL.md §3) in the viewer's frame (the dataset frame
// shifted so that the centre of its bounds is 0, keeping Float32 precision on the GPU).
import * as THREE from 'three';

export class TileNode {
  // grid: {min: [x,y,z] (shifted frame), voxelSize (finest), tileDepth, finestLevel}
  constructor(level, x, y, z, voxels, grid) {
    this.level = level;
    this.x = x;
    this.y = y;
    this.z = z;
    this.voxels = voxels;
    this.key = TileNode.key(level, x, y, z);
    this.voxelSize = grid.voxelSize * 2 ** (grid.finestLevel - level);
    const edge = this.voxelSize * 2 ** grid.tileDepth;
    const min = new THREE.Vector3(grid.min[0] + x * edge, grid.min[1] + y * edge, grid.min[2] + z * edge);
    this.box = new THREE.Box3(min, min.clone().addScalar(edge)); // nominal; tight once loaded
    this.parent = null;
    this.children = null; // null: not known yet (its hierarchy page is still to fetch); [] for a leaf
    this.points = null; // THREE.Points once decoded
    this.state = 'idle'; // idle | loading | ready | failed
    this.lastUsed = -1; // frame number of the last traversal that reached it
  }

  static key(level, x, y, z) {
    return `${level}/${x}/${y}/${z}`;
  }

  path() {
    return `${this.level}/${this.x}/${this.y}/${this.z}`;
  }

  // The tile's points arrived: from now on its box is the tight box of its voxels.
  setPoints(points) {
    this.points = points;
    this.state = 'ready';
    points.geometry.computeBoundingBox();
    this.box.copy(points.geometry.boundingBox).applyMatrix4(points.matrix);
    this.box.max.addScalar(this.voxelSize / 2);
    this.box.min.subScalar(this.voxelSize / 2);
  }

  // Back to 'idle' after eviction or a failure; the caller disposes of the GPU buffers.
  unload(state = 'idle') {
    this.points = null;
    this.state = state;
  }
}
