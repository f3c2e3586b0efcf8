// Which tiles exist: walks GET /v1/datasets/{id}/hierarchy/L/X/Y/Z pages lazily (PROTOCOL.md §3).
// A node listed in a page's `pages` has children that only its own page names; the viewer asks
// for that page when it wants to refine the node.
import { TileNode } from './tile_node.js';

const MAX_PAGES_IN_FLIGHT = 2;

export class TileHierarchy {
  // pageDepth: levels per page (the query's depth), null for the daemon's default.
  constructor(api, datasetId, grid, pageDepth = null) {
    this.api = api;
    this.datasetId = datasetId;
    this.grid = grid;
    this.query = pageDepth === null ? '' : `?depth=${pageDepth}`;
    this.nodes = new Map();
    this.root = null;
    this.pending = new Set(); // keys of pages being fetched
    this.failed = new Set();
    this.pagesRead = 0;
    this.onChange = () => {};
  }

  async loadRoot() {
    await this.loadPage(0, 0, 0, 0);
    this.root = this.nodes.get(TileNode.key(0, 0, 0, 0));
    if (!this.root) throw new Error('the dataset has no root tile');
  }

  // Asks for the node's page unless it is known, being fetched, or too many pages are in flight.
  requestChildren(node) {
    if (node.children || this.pending.has(node.key) || this.failed.has(node.key)) return;
    if (this.pending.size >= MAX_PAGES_IN_FLIGHT) return;
    this.loadPage(node.level, node.x, node.y, node.z)
      .catch((err) => {
        this.failed.add(node.key);
        console.error(`hierarchy page ${node.key}: ${err.message}`);
      })
      .finally(() => this.onChange());
  }

  get loading() {
    return this.pending.size;
  }

  async loadPage(level, x, y, z) {
    const key = TileNode.key(level, x, y, z);
    this.pending.add(key);
    try {
      const page = await this.api.json(`/v1/datasets/${encodeURIComponent(this.datasetId)}/hierarchy/${key}${this.query}`);
      this.merge(page);
      this.pagesRead++;
    } finally {
      this.pending.delete(key);
    }
  }

  merge(page) {
    const deepest = page.node.level + page.depth;
    const paged = new Set(page.pages.map((p) => TileNode.key(p.level, p.x, p.y, p.z)));
    const added = [];
    for (const t of page.tiles) {
      const key = TileNode.key(t.level, t.x, t.y, t.z);
      let node = this.nodes.get(key);
      if (!node) {
        node = new TileNode(t.level, t.x, t.y, t.z, t.voxels, this.grid);
        this.nodes.set(key, node);
      }
      added.push(node);
    }
    for (const node of added) {
      // A node above the page's deepest level has all its children in the page; one at that
      // level has none unless `pages` lists it.
      if (!node.children && (node.level < deepest || !paged.has(node.key))) node.children = [];
    }
    for (const node of added) {
      if (node.level === page.node.level) continue;
      const parent = this.nodes.get(TileNode.key(node.level - 1, node.x >> 1, node.y >> 1, node.z >> 1));
      if (parent && !node.parent) {
        node.parent = parent;
        parent.children.push(node);
      }
    }
  }
}
