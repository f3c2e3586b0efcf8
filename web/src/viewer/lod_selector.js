// Chooses the tiles of a frame by screen-space error within a budget of resident points, with
// REPLACE refinement: a tile in the frustum whose voxels project larger than `thresholdPx` pixels
// is replaced by its children in the frustum, but only once all of them can be drawn; until then
// the tile itself stays drawn, so no hole opens.
//
// The plan: tiles are refined coarsest level first, nearest first within a level, as long as the
// tiles the plan needs fit the budget. A refinement still loading needs the tile and its children
// at once (the tile stays drawn meanwhile); once its children are all ready the tile is no longer
// needed and its room goes to finer tiles. A refinement that does not fit is not started, so no
// loaded-but-undrawable children hold the budget. Tiles outside the plan are evictable.
import * as THREE from 'three';

export class LodSelector {
  constructor(hierarchy, finestLevel, thresholdPx) {
    this.hierarchy = hierarchy;
    this.finestLevel = finestLevel;
    this.thresholdPx = thresholdPx;
    this.frustum = new THREE.Frustum();
    this.matrix = new THREE.Matrix4();
  }

  // Returns {draw: [node], wanted: [{node, distance}], pagesWanted, covered, budgetLimited, plannedPoints}:
  // draw, what the frame shows; wanted, the plan's tiles still to load. Marks the tiles in the
  // frustum with lastUsed = frame and those the plan needs resident with keep = frame.
  select(camera, heightPx, frame, budgetPoints = Infinity) {
    this.matrix.multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
    this.frustum.setFromProjectionMatrix(this.matrix);
    this.eye = camera.getWorldPosition(new THREE.Vector3());
    this.near = camera.near;
    // Pixels per world unit at distance 1.
    this.pxPerUnit = heightPx / (2 * Math.tan(THREE.MathUtils.degToRad(camera.fov / 2)));
    this.frame = frame;
    this.result = { draw: [], wanted: [], pagesWanted: false, covered: true, budgetLimited: false, plannedPoints: 0 };
    const root = this.hierarchy.root;
    if (!this.inView(root)) return this.result;
    this.plan(root, budgetPoints);
    this.result.covered = this.visit(root);
    return this.result;
  }

  // Marks a node in the frustum as seen in this frame and gives its distance; null outside.
  inView(node) {
    if (!this.frustum.intersectsBox(node.box)) return null;
    node.lastUsed = this.frame;
    node.distance = Math.max(node.box.distanceToPoint(this.eye), this.near);
    return node;
  }

  plan(root, budget) {
    // A tile is settled when it is ready, or was covered by its ready descendants last frame (it
    // may have been evicted since: it need not be loaded again, nor counted).
    const settled = (node) => node.state === 'ready' || node.coveredFrame === this.frame - 1;
    const keep = (node) => {
      node.counted = node.state !== 'ready' && settled(node) ? 0 : node.voxels;
      if (!node.counted) return 0;
      node.keep = this.frame;
      if (node.state === 'idle') this.result.wanted.push({ node, distance: node.distance });
      return node.counted;
    };
    let cost = keep(root); // the root is always planned (loaded over the budget if need be)
    let level = [root];
    while (level.length) {
      level.sort((a, b) => a.distance - b.distance);
      const next = [];
      for (const node of level) {
        if (!this.wantsChildren(node)) continue;
        const children = node.children.filter((c) => this.inView(c));
        if (!children.length) continue;
        const add = children.reduce((n, c) => n + (c.state !== 'ready' && settled(c) ? 0 : c.voxels), 0);
        // Children all settled: the node is no longer drawn, its room is free.
        const freed = children.every(settled) ? node.counted : 0;
        if (cost + add - freed > budget) {
          this.result.budgetLimited = true;
          continue;
        }
        node.refine = this.frame;
        if (freed) {
          node.keep = -1;
          node.counted = 0;
        }
        cost -= freed;
        for (const c of children) {
          cost += keep(c);
          next.push(c);
        }
      }
      level = next;
    }
    this.result.plannedPoints = cost;
  }

  // True when the node's part of the view is drawn (by it, its descendants, or nothing is needed).
  visit(node) {
    if (node.lastUsed !== this.frame) return true; // outside the frustum
    if (node.refine === this.frame) {
      const mark = this.result.draw.length;
      let covered = true;
      for (const child of node.children) covered = this.visit(child) && covered;
      if (covered) {
        node.coveredFrame = this.frame;
        return true;
      }
      this.result.draw.length = mark; // the children are incomplete: draw the node instead
    }
    if (node.state !== 'ready') return false;
    this.result.draw.push(node);
    node.coveredFrame = this.frame;
    return true;
  }

  wantsChildren(node) {
    if (node.level >= this.finestLevel) return false;
    if ((node.voxelSize * this.pxPerUnit) / node.distance <= this.thresholdPx) return false;
    if (node.children === null) {
      this.result.pagesWanted = true;
      this.hierarchy.requestChildren(node);
      return false;
    }
    return node.children.length > 0;
  }
}
