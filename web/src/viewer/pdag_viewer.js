// Streams a dataset's .pdag tiles (GET /v1/datasets/{id}/tiles/...) into a SceneView: hierarchy
// pages on demand, tiles chosen per frame by LodSelector, fetched by TileLoader, decoded in a
// DecoderPool of Web Workers, kept by TileCache within a budget of points. A dataset with shadows
// can shade its points by their light (setShadows), from per-tile layers fetched once turned on.
/* global POINTDAG_WORKER_URL, POINTDAG_WASM_URL */
import { formatBytes, formatInt } from '../app/format.js';
import { DecoderPool } from './decoder_pool.js';
import { heightRange, paintByHeight } from './height_colors.js';
import { LodSelector } from './lod_selector.js';
import { PointMaterials } from './point_materials.js';
import { positiveParam } from './query_param.js';
import { boxCorners } from './scene_view.js';
import { ShadowLayers } from './shadow_layers.js';
import { probeVoxelLight } from './shadow_probe.js';
import { SHADOW_AMBIENT, ShadowShading } from './shadow_shading.js';
import { shadowRow, statRows } from './stat_rows.js';
import { TileCache } from './tile_cache.js';
import { TileHierarchy } from './tile_hierarchy.js';
import { TileLoader } from './tile_loader.js';

// Decode workers: one per core beside the page's own, at least 2 (decoding and fetching overlap), at most 4.
const DEFAULTS = {
  budget: 10_000_000, sse: 1.5, inflight: 6,
  workers: Math.min(4, Math.max(2, (navigator.hardwareConcurrency || 2) - 1)),
};

// The decode worker (contract 2), told where the WebAssembly decoder is when the build has one.
const WORKER_URL = POINTDAG_WASM_URL
  ? `${POINTDAG_WORKER_URL}?wasm=${encodeURIComponent(POINTDAG_WASM_URL)}` : POINTDAG_WORKER_URL;

function numberParam(params, name) {
  return positiveParam(params, name, DEFAULTS[name]);
}

export class PdagViewer {
  // params: the page's query (?budget=POINTS, ?sse=PIXELS, ?inflight=N, ?workers=N, ?decoder=js|wasm,
  // ?pagedepth=LEVELS of each hierarchy page).
  constructor(view, api, dataset, params) {
    this.view = view;
    this.dataset = dataset;
    const { min, max } = dataset.bounds;
    this.frameOrigin = min.map((v, i) => (v + max[i]) / 2); // the viewer's frame: centred on the bounds
    const grid = {
      min: min.map((v, i) => v - this.frameOrigin[i]),
      voxelSize: dataset.voxel_size,
      tileDepth: dataset.tile_depth,
      finestLevel: dataset.levels - 1,
    };
    this.hierarchy = new TileHierarchy(api, dataset.id, grid, positiveParam(params, 'pagedepth', null));
    this.hierarchy.onChange = () => view.requestRender();
    this.selector = new LodSelector(this.hierarchy, grid.finestLevel, numberParam(params, 'sse'));
    this.cache = new TileCache(view.scene, numberParam(params, 'budget'));
    this.shadows = dataset.shadows
      ? new ShadowLayers(api, dataset.id, new ShadowShading(), () => view.requestRender()) : null;
    const backend = params.get('decoder') || undefined;
    this.pool = new DecoderPool(WORKER_URL, numberParam(params, 'workers'), backend);
    this.loader = new TileLoader({
      api, datasetId: dataset.id, pool: this.pool, cache: this.cache,
      materials: new PointMaterials(view.camera), frameOrigin: this.frameOrigin,
      maxInFlight: numberParam(params, 'inflight'),
      onLoaded: (node) => this.tileLoaded(node),
      shadows: this.shadows,
      paint: (points) => paintByHeight(points, points.matrix, view.upAxis, this.heights(points)),
    });
    this.frame = 0;
    this.drawn = [];
    this.complete = false;
    this.firstFrameMs = null;
    this.finestMs = null;
    this.userMoved = false;
    view.onUserMove(() => { this.userMoved = true; });
    view.onFrame = () => this.update();
  }

  async start() {
    await this.hierarchy.loadRoot();
    this.view.fit(this.dataBox());
  }

  // The dataset's box in the viewer's frame: the root tile's tight box once decoded (it holds
  // every voxel of every level), the bounds' cube before.
  dataBox() {
    return this.hierarchy.root.box;
  }

  // Before the root page is read there is nothing to fit (start() fits once it is).
  fit() {
    if (this.hierarchy.root) this.view.fit(this.dataBox());
  }

  // The heights that colors span along the view's up axis (height_colors.js): those of the first tile
  // painted (the root), kept until the axis changes.
  heights(points) {
    if (!this.heightSpan || this.heightSpan.axis !== this.view.upAxis) {
      this.heightSpan = { axis: this.view.upAxis, range: heightRange(points, points.matrix, this.view.upAxis) };
    }
    return this.heightSpan.range;
  }

  // After the view's up axis changed: tiles colored by height take the new heights (the root's).
  upAxisChanged() {
    const painted = [...this.cache.tiles].filter((node) => node.points?.userData.paintedByHeight);
    if (!painted.length) return;
    const root = painted.find((node) => node === this.hierarchy.root) || painted[0];
    this.heightSpan = null;
    const heights = this.heights(root.points);
    for (const node of painted) paintByHeight(node.points, node.points.matrix, this.view.upAxis, heights);
    this.view.requestRender();
  }

  // The darkest shading (a voxel never lit): the toggle's legend shows it.
  get shadowAmbient() {
    return SHADOW_AMBIENT;
  }

  // Shading by the shadow layers on or off (a dataset without shadows has none to turn on).
  setShadows(on) {
    if (!this.shadows) return;
    this.shadows.setEnabled(on, this.cache.tiles);
  }

  tileLoaded(node) {
    if (node === this.hierarchy.root && !this.userMoved) this.fit();
    this.cache.trim(this.frame);
    this.view.requestRender();
  }

  update() {
    if (!this.hierarchy.root) return; // start() has not read the root page yet
    const frame = ++this.frame;
    const sel = this.selector.select(this.view.camera, this.view.heightPx(), frame, this.cache.budget);
    for (const node of this.drawn) if (node.points) node.points.visible = false;
    for (const node of sel.draw) node.points.visible = true;
    this.drawn = sel.draw;
    this.loader.schedule(sel.wanted, (points) => this.cache.makeRoom(points, frame));
    this.cache.trim(frame);
    const now = performance.now();
    if (this.firstFrameMs === null && sel.draw.length) this.firstFrameMs = now;
    // Finest visible level drawn: nothing more to fetch for this view (or nothing the budget allows:
    // the selector plans only what fits, and a tile the loader could not make room for is neither
    // in flight nor queued).
    this.complete = sel.covered && !sel.pagesWanted && this.loader.inFlight === 0 &&
      this.loader.queued === 0 && sel.draw.length > 0;
    if (this.complete && this.finestMs === null) this.finestMs = now;
  }

  state() {
    const levels = [...new Set(this.drawn.map((n) => n.level))].sort((a, b) => a - b);
    return {
      finestVisibleLevelDrawn: this.complete,
      levelsDrawn: levels,
      tilesOnScreen: this.drawn.length,
      pointsOnScreen: this.drawn.reduce((n, t) => n + t.voxels, 0),
      loading: this.loader.inFlight + this.loader.queued + this.hierarchy.loading,
      firstFrameMs: this.firstFrameMs,
      finestMs: this.finestMs,
      bytesFetched: this.loader.bytes,
      tilesFetched: this.loader.loaded,
      hierarchyPages: this.hierarchy.pagesRead,
      residentPoints: this.cache.points,
      evictedTiles: this.cache.evicted,
      budgetPoints: this.cache.budget,
      decoder: { backend: this.pool.backendUsed, tiles: this.pool.decoded, ms: this.pool.decodeMs, voxels: this.pool.decodedVoxels },
      errors: this.loader.failures,
      lastError: this.loader.lastError,
      shadows: this.shadows && this.shadows.state(this.drawn),
    };
  }

  // Test hook: up to `limit` visible voxels of shaded tiles, with the CSS pixel of their centre.
  shadowProbe(limit) {
    return probeVoxelLight(this.drawn, this.view, limit);
  }

  projectedBounds() {
    return this.view.project(boxCorners(this.dataBox()));
  }

  statRows() {
    const s = this.state();
    return statRows(s, this.view.frameMs, `${formatBytes(s.bytesFetched)} in ${s.tilesFetched} tiles`, [
      ['Resident', `${formatInt(s.residentPoints)} / ${formatInt(s.budgetPoints)} points`],
      ['Decode', s.decoder.tiles ? `${(s.decoder.ms / s.decoder.tiles).toFixed(1)} ms/tile (${s.decoder.backend})` : '–'],
      ...(s.shadows ? [shadowRow(s)] : []),
    ]);
  }
}
