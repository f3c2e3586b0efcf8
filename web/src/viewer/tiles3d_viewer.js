// The same dataset drawn from its 3D Tiles 1.1 tileset (GET /v1/datasets/{id}/3dtiles/tileset.json,
// .glb point tiles with EXT_meshopt_compression + KHR_mesh_quantization) by 3d-tiles-renderer.
// The tileset's root transform is ENU->ECEF: the tiles group sits under its inverse, shifted to the
// centre of the dataset's bounds, so this view shares PdagViewer's frame and camera. Shadows shade
// the points as in PdagViewer: a .glb holds the tile's voxels in the Morton order of its layer.
import * as THREE from 'three';
import { TilesRenderer } from '3d-tiles-renderer';
import { GLTFExtensionsPlugin } from '3d-tiles-renderer/plugins';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
import { formatBytes } from '../app/format.js';
import { heightRange, paintByHeight } from './height_colors.js';
import { ByteCounterPlugin } from './byte_counter_plugin.js';
import { worldPointSize } from './point_materials.js';
import { positiveParam } from './query_param.js';
import { boxCorners } from './scene_view.js';
import { ShadowLayers } from './shadow_layers.js';
import { probeVoxelLight } from './shadow_probe.js';
import { SHADOW_AMBIENT, ShadowShading } from './shadow_shading.js';
import { shadowRow, statRows } from './stat_rows.js';

const TILE_OF_URL = /(?:^|\/)((\d+)\/\d+\/\d+\/\d+)\.glb(?:\?|$)/; // tiles are L/X/Y/Z.glb: [, path, level]

export class Tiles3dViewer {
  // params: ?sse=PIXELS (as PdagViewer: refine while a voxel projects larger than this).
  constructor(view, api, dataset, params) {
    this.view = view;
    this.dataset = dataset;
    this.sse = positiveParam(params, 'sse', 1.5);
    const { min, max } = dataset.bounds;
    this.centre = new THREE.Vector3(...min.map((v, i) => (v + max[i]) / 2));
    this.tiles = new TilesRenderer(`/v1/datasets/${encodeURIComponent(dataset.id)}/3dtiles/tileset.json`);
    this.tiles.fetchOptions = { headers: api.tokens.headers() };
    this.byteCounter = new ByteCounterPlugin();
    this.tiles.registerPlugin(this.byteCounter);
    this.tiles.registerPlugin(new GLTFExtensionsPlugin({ meshoptDecoder: MeshoptDecoder }));
    this.tiles.setCamera(view.camera);
    this.tiles.setResolutionFromRenderer(view.camera, view.renderer);
    this.frameGroup = new THREE.Group(); // the dataset frame, centred: inverse of the root transform
    this.frameGroup.matrixAutoUpdate = false;
    this.frameGroup.add(this.tiles.group);
    view.scene.add(this.frameGroup);
    this.tiles.addEventListener('needs-update', () => view.requestRender());
    this.shadows = dataset.shadows
      ? new ShadowLayers(api, dataset.id, new ShadowShading(), () => view.requestRender()) : null;
    this.shadowTiles = new Map(); // a model's scene -> its stand-in for ShadowLayers
    this.painted = new Map(); // a model's scene -> its Points colored by height (a scan without color)
    this.heightSpan = null;
    this.tiles.addEventListener('load-model', (e) => {
      this.styleModel(e.scene, e.url);
      this.adoptShadows(e.scene, e.url);
    });
    this.tiles.addEventListener('dispose-model', (e) => {
      this.dropShadows(e.scene);
      this.painted.delete(e.scene);
    });
    this.tiles.addEventListener('load-error', (e) => { this.lastError = `${e.url}: ${e.error.message}`; });
    this.complete = false;
    this.firstFrameMs = null;
    this.finestMs = null;
    this.lastError = null;
    view.onFrame = () => this.update();
  }

  start() {
    return new Promise((resolve, reject) => {
      this.tiles.addEventListener('load-root-tileset', ({ tileset }) => {
        this.useTileset(tileset);
        resolve();
      });
      this.tiles.addEventListener('load-error', (e) => { if (!e.tile) reject(new Error(`${e.url}: ${e.error.message}`)); });
      this.view.requestRender(); // the first update() fetches tileset.json
    });
  }

  useTileset(tileset) {
    const transform = new THREE.Matrix4();
    if (tileset.root.transform) transform.fromArray(tileset.root.transform);
    this.frameGroup.matrix.copy(transform).invert().premultiply(new THREE.Matrix4().makeTranslation(this.centre.clone().negate()));
    this.frameGroup.updateMatrixWorld(true);
    // Our geometric errors are a multiple of the voxel size: scale the pixel target alike.
    const voxel0 = this.dataset.voxel_size * 2 ** (this.dataset.levels - 1);
    if (tileset.root.geometricError > 0) this.tiles.errorTarget = (this.sse * tileset.root.geometricError) / voxel0;
    this.fit();
  }

  // glTF points are 1 px wide: make them as wide as their level's voxel, as in PdagViewer.
  styleModel(scene, url) {
    const match = String(url).match(TILE_OF_URL);
    if (!match) return;
    const level = Number(match[2]);
    const voxel = this.dataset.voxel_size * 2 ** (this.dataset.levels - 1 - level);
    scene.traverse((obj) => {
      if (!obj.isPoints) return;
      obj.material.size = worldPointSize(voxel, this.view.camera);
      obj.material.sizeAttenuation = true;
      if (!obj.geometry.attributes.color) this.paint(scene, obj, level);
      obj.material.vertexColors = !!obj.geometry.attributes.color;
      obj.material.needsUpdate = true;
    });
  }

  // A tile without colors by height (height_colors.js), in linear colors as glTF's; the heights span
  // the root tile's, as on the .pdag page (a tile that arrives before the root lends its own until then).
  paint(scene, points, level) {
    this.painted.set(scene, { points, level });
    const axis = this.view.upAxis;
    const span = this.heightSpan;
    if (!span || span.axis !== axis || (level === 0 && span.level !== 0)) {
      this.heightSpan = { axis, level, range: heightRange(points, this.frameMatrix(scene, points), axis) };
      if (span) return this.repaint(); // the tiles painted with the old span, this one among them
    }
    paintByHeight(points, this.frameMatrix(scene, points), axis, this.heightSpan.range, { linear: true });
  }

  repaint() {
    for (const [scene, { points }] of this.painted) {
      paintByHeight(points, this.frameMatrix(scene, points), this.view.upAxis, this.heightSpan.range, { linear: true });
    }
    this.view.requestRender();
  }

  // The points' matrix into the viewer's frame, from the glTF alone (PROTOCOL.md §3.1: the node maps
  // a cell into glTF's y-up frame, 3D Tiles turns that z-up into the tileset's frame, whose root
  // transform the frame group undoes, less the centre): the model's own root matrix, which the
  // renderer sets as it places the model, is not read.
  frameMatrix(scene, points) {
    const matrix = new THREE.Matrix4();
    for (let obj = points; obj && obj !== scene; obj = obj.parent) {
      if (obj.matrixAutoUpdate) obj.updateMatrix();
      matrix.premultiply(obj.matrix);
    }
    return matrix.premultiply(new THREE.Matrix4().makeRotationX(Math.PI / 2))
      .premultiply(new THREE.Matrix4().makeTranslation(this.centre.clone().negate()));
  }

  // After the view's up axis changed: tiles colored by height take the new heights (the root's, or
  // the coarsest tile's at hand).
  upAxisChanged() {
    if (!this.painted.size) return;
    const [scene, { points, level }] = [...this.painted].reduce((a, b) => (b[1].level < a[1].level ? b : a));
    this.heightSpan = { axis: this.view.upAxis, level, range: heightRange(points, this.frameMatrix(scene, points), this.view.upAxis) };
    this.repaint();
  }

  // The model's stand-in for ShadowLayers: {points, voxels, path()} of its one Points object.
  adoptShadows(scene, url) {
    const match = String(url).match(TILE_OF_URL);
    if (!this.shadows || !match) return;
    let points = null;
    scene.traverse((obj) => { if (obj.isPoints) points = obj; });
    if (!points) return;
    const node = { points, plain: points.material, voxels: points.geometry.attributes.position.count, path: () => match[1] };
    this.shadowTiles.set(scene, node);
    this.shadows.adopt(node);
  }

  // The renderer disposes of the model's geometry and its (shaded) material; the plain one goes too.
  dropShadows(scene) {
    const node = this.shadowTiles.get(scene);
    if (!node) return;
    this.shadowTiles.delete(scene);
    if (node.points.material !== node.plain) node.plain.dispose();
    node.points = null; // a layer still on its way is dropped
  }

  get shadowAmbient() {
    return SHADOW_AMBIENT;
  }

  setShadows(on) {
    if (this.shadows) this.shadows.setEnabled(on, this.shadowTiles.values());
  }

  visibleShadowTiles() {
    return this.visibleTiles().map((t) => this.shadowTiles.get(t.engineData.scene)).filter(Boolean);
  }

  // Test hook, as PdagViewer's.
  shadowProbe(limit) {
    return probeVoxelLight(this.visibleShadowTiles(), this.view, limit);
  }

  // The root tile's bounding box, in the viewer's frame.
  dataCorners() {
    const box = new THREE.Box3();
    const matrix = new THREE.Matrix4();
    if (!this.tiles.getOrientedBoundingBox(box, matrix)) return null;
    return boxCorners(box, matrix.premultiply(this.tiles.group.matrixWorld));
  }

  fit() {
    const corners = this.dataCorners();
    if (corners) this.view.fit(new THREE.Box3().setFromPoints(corners));
  }

  update() {
    this.view.scene.updateMatrixWorld();
    this.tiles.update();
    const visible = this.visibleTiles().length;
    const now = performance.now();
    if (this.firstFrameMs === null && visible > 0) this.firstFrameMs = now;
    // Nothing requested, downloading, parsing, or waiting to have its children expanded.
    const t = this.tiles;
    // The queues can be empty between a download's end and its parse being queued: the stats say
    // what is still on its way.
    const s = t.stats;
    const busy = t.isLoading || t.downloadQueue.running || t.parseQueue.running || t.processNodeQueue.running ||
      s.queued + s.downloading + s.parsing > 0;
    this.complete = !!t.root && !busy && visible > 0;
    if (this.complete && this.finestMs === null) this.finestMs = now;
    if (busy) this.view.requestRender(); // keep traversing while tiles stream in
  }

  visibleTiles() {
    return [...this.tiles.visibleTiles].filter((t) => t.engineData && t.engineData.scene);
  }

  state() {
    const levels = new Set();
    let points = 0;
    for (const tile of this.visibleTiles()) {
      const match = tile.content && String(tile.content.uri).match(TILE_OF_URL);
      if (match) levels.add(Number(match[2]));
      tile.engineData.scene.traverse((obj) => { if (obj.isPoints) points += obj.geometry.attributes.position.count; });
    }
    const s = this.tiles.stats;
    return {
      finestVisibleLevelDrawn: this.complete,
      levelsDrawn: [...levels].sort((a, b) => a - b),
      tilesOnScreen: this.visibleTiles().length,
      pointsOnScreen: points,
      loading: s.queued + s.downloading + s.parsing,
      firstFrameMs: this.firstFrameMs,
      finestMs: this.finestMs,
      bytesFetched: this.byteCounter.tileBytes,
      tilesFetched: this.byteCounter.tiles,
      tilesetBytes: this.byteCounter.otherBytes,
      lastError: this.lastError,
      shadows: this.shadows && this.shadows.state(this.visibleShadowTiles()),
    };
  }

  projectedBounds() {
    const corners = this.dataCorners();
    return corners ? this.view.project(corners) : null;
  }

  statRows() {
    const s = this.state();
    return statRows(s, this.view.frameMs,
      `${formatBytes(s.bytesFetched)} in ${s.tilesFetched} tiles (+ ${formatBytes(s.tilesetBytes)} tileset.json)`,
      s.shadows ? [shadowRow(s)] : []);
  }
}
