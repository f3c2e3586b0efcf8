// The tiles resident on the GPU, within a budget of points. Tiles the current plan does not keep
// (node.keep, set by LodSelector) stay cached while the budget has room; when a load needs room,
// they go first, least recently in view first, finest first among equals (tiles that fell out of
// view, were replaced by finer ones, or belong to a refinement the budget gave up).
export class TileCache {
  constructor(scene, budgetPoints) {
    this.scene = scene;
    this.budget = budgetPoints;
    this.tiles = new Set();
    this.points = 0;
    this.evicted = 0;
  }

  add(node, points) {
    node.setPoints(points);
    this.scene.add(points);
    this.tiles.add(node);
    this.points += node.voxels;
  }

  // Evicts tiles the plan of frame `frame` does not keep until `points` more fit the budget;
  // true when they do.
  makeRoom(points, frame) {
    if (this.points + points <= this.budget) return true;
    const unkept = [...this.tiles].filter((n) => n.keep !== frame)
      .sort((a, b) => a.lastUsed - b.lastUsed || b.level - a.level);
    for (const node of unkept) {
      if (this.points + points <= this.budget) break;
      this.evict(node);
    }
    return this.points + points <= this.budget;
  }

  // Back within the budget (a tile arrived for a plan that changed meanwhile).
  trim(frame) {
    this.makeRoom(0, frame);
  }

  evict(node) {
    this.scene.remove(node.points);
    node.points.geometry.dispose();
    this.tiles.delete(node);
    this.points -= node.voxels;
    this.evicted++;
    node.unload();
  }
}
