// Fetches and decodes the tiles a frame asks for: coarsest level first, then nearest, with at most
// `maxInFlight` tiles between request and decoded points. Each frame replaces the queue, so what
// left the view is never fetched. With shadows wanted, each tile's shadow layer is fetched beside it.
import { buildTilePoints } from './tile_points.js';

export class TileLoader {
  // shadows: ShadowLayers, or null for a dataset without shadows.
  constructor({ api, datasetId, pool, cache, materials, frameOrigin, maxInFlight, onLoaded, shadows = null, paint = null }) {
    Object.assign(this, { api, datasetId, pool, cache, materials, frameOrigin, maxInFlight, onLoaded, shadows, paint });
    this.queue = [];
    this.inFlight = 0;
    this.inFlightPoints = 0;
    this.bytes = 0;
    this.loaded = 0;
    this.failures = 0;
    this.lastError = null;
  }

  // wanted: [{node, distance}] of tiles the frame needs and lacks; makeRoom(voxels) frees room in
  // the budget for that many more points (evicting what the frame does not keep), true if it could.
  schedule(wanted, makeRoom) {
    wanted.sort((a, b) => a.node.level - b.node.level || a.distance - b.distance);
    this.queue = wanted.map((w) => w.node);
    this.blockedByBudget = 0;
    while (this.inFlight < this.maxInFlight && this.queue.length) {
      const node = this.queue.shift();
      // The root always loads: without it nothing can be drawn.
      if (!makeRoom(node.voxels + this.inFlightPoints) && node.level > 0) {
        this.blockedByBudget++;
        continue;
      }
      this.load(node);
    }
  }

  get queued() {
    return this.queue.length;
  }

  async load(node) {
    node.state = 'loading';
    this.inFlight++;
    this.inFlightPoints += node.voxels;
    const layer = this.shadows?.wanted ? this.shadows.fetch(node) : null; // never rejects
    try {
      const bytes = await this.api.bytes(`/v1/datasets/${encodeURIComponent(this.datasetId)}/tiles/${node.path()}`);
      this.bytes += bytes.byteLength;
      const decoded = await this.pool.decode(bytes);
      if (decoded.count !== node.voxels) {
        throw new Error(`decoded ${decoded.count} voxels, the hierarchy says ${node.voxels}`);
      }
      this.cache.add(node, buildTilePoints(decoded, this.frameOrigin, this.materials, this.paint));
      this.shadows?.adopt(node, layer);
      this.loaded++;
    } catch (err) {
      node.unload('failed');
      this.failures++;
      this.lastError = `tile ${node.path()}: ${err.message}`;
      console.error(this.lastError);
    } finally {
      this.inFlight--;
      this.inFlightPoints -= node.voxels;
      this.onLoaded(node);
    }
  }
}
