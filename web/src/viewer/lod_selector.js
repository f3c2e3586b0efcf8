// Chooses the tiles of a frame by screen-space error: a tile in the frustum whose voxels project
// larger than `thresholdPx` pixels is replaced by its children (REPLACE refinement), but only once
// every child in the frustum can be drawn; until then the tile itself stays drawn, so no hole opens.
import * as THREE from 'three';

export class LodSelector {
  constructor(hierarchy, finestLevel, thresholdPx) {
    this.hierarchy = hierarchy;
    this.finestLevel = finestLevel;
    this.thresholdPx = thresholdPx;
    this.frustum = new THREE.Frustum();
    this.matrix = new THREE.Matrix4();
  }

  // Returns {draw: [node], wanted: [{node, distance}], pagesWanted: bool, covered: bool};
  // marks every node in the frustum as used in `frame`.
  select(camera, heightPx, frame) {
    this.matrix.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
    this.frustum.setFromProjectionMatrix(this.matrix);
    this.eye = camera.getWorldPosition(new THREE.Vector3());
    this.near = camera.near;
    // Pixels per world unit at distance 1.
    this.pxPerUnit = heightPx / (2 * Math.tan(THREE.MathUtils.degToRad(camera.fov / 2)));
    this.frame = frame;
    this.result = { draw: [], wanted: [], pagesWanted: false, covered: false };
    this.result.covered = this.visit(this.hierarchy.root);
    return this.result;
  }

  // True when the node's part of the view is drawn (by it, its descendants, or nothing is needed).
  visit(node) {
    if (!this.frustum.intersectsBox(node.box)) return true;
    node.lastUsed = this.frame;
    const distance = Math.max(node.box.distanceToPoint(this.eye), this.near);
    if (node.state === 'idle') this.result.wanted.push({ node, distance });
    if (this.wantsChildren(node, distance)) {
      const mark = this.result.draw.length;
      let covered = true;
      for (const child of node.children) covered = this.visit(child) && covered;
      if (covered) return true;
      this.result.draw.length = mark; // the children are incomplete: draw the node instead
    }
    if (node.state !== 'ready') return false;
    this.result.draw.push(node);
    return true;
  }

  wantsChildren(node, distance) {
    if (node.level >= this.finestLevel) return false;
    if ((node.voxelSize * this.pxPerUnit) / distance <= this.thresholdPx) return false;
    if (node.children === null) {
      this.result.pagesWanted = true;
      this.hierarchy.requestChildren(node);
      return false;
    }
    return node.children.length > 0;
  }
}
