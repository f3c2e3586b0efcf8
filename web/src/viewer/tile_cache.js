// The tiles resident on the GPU, within a budget of points: what the last frames did not use goes
// first, least recently used first (tiles that fell out of view, or were replaced by finer ones).
export class TileCache {
  constructor(scene, budgetPoints) {
    this.scene = scene;
    this.budget = budgetPoints;
    this.tiles = new Set();
    this.points = 0;
  }

  add(node, points) {
    node.setPoints(points);
    this.scene.add(points);
    this.tiles.add(node);
    this.points += node.voxels;
  }

  // Points of the tiles the frame `frame` used: what must stay resident.
  pointsUsedIn(frame) {
    let n = 0;
    for (const node of this.tiles) if (node.lastUsed === frame) n += node.voxels;
    return n;
  }

  // Evicts tiles the current frame does not use until the budget holds.
  trim(frame) {
    if (this.points <= this.budget) return;
    const unused = [...this.tiles].filter((n) => n.lastUsed < frame).sort((a, b) => a.lastUsed - b.lastUsed);
    for (const node of unused) {
      if (this.points <= this.budget) break;
      this.evict(node);
    }
  }

  evict(node) {
    this.scene.remove(node.points);
    node.points.geometry.dispose();
    this.tiles.delete(node);
    this.points -= node.voxels;
    node.unload();
  }
}
