// `/datasets/{id}` (kind 'pdag': our .pdag tiles, decoded in Web Workers) and
// `/datasets/{id}/3dtiles` (kind '3dtiles': the 3D Tiles tileset drawn by 3d-tiles-renderer):
// a full-window scene, a top bar, and the HUD. Both expose the test hooks of contract 5 as
// window.pointdagViewer. Both choose which axis points up (?up=z|y|-y, remembered per dataset). The
// pages of a dataset with shadows have a "Shadows" toggle (?shadows=1 starts with it on).
import { h } from './dom.js';
import { formatBytes, formatDracoRatio, formatFixed, formatInt, formatLength } from './format.js';
import { Hud } from './hud.js';
import { ShadowToggle } from './shadow_toggle.js';
import { UpAxisSelect } from './up_axis_select.js';

const HUD_MS = 250;

function crsText(frame) {
  if (!frame.georeferenced) return 'none (the scan\'s own units)';
  return frame.epsg ? `${frame.crs_name} (EPSG:${frame.epsg})` : frame.crs_name;
}

function metaRows(d) {
  const f = d.frame;
  const o = f.enu_origin;
  return [
    ['Dataset', d.name],
    ['CRS', crsText(f)],
    ['Origin', o ? `${formatFixed(o.lat, 6)}°, ${formatFixed(o.lon, 6)}°, h ${formatFixed(o.h, 1)} m` : '–'],
    ['Voxel', formatLength(d.voxel_size, f.georeferenced)],
    ['Levels', `${d.levels} (depth ${d.depth}, ${formatInt(d.tile_count)} tiles)`],
    ['Points', `${formatInt(d.source.points)} → ${formatInt(d.voxels)} voxels`],
    ['Stored', formatBytes(d.stored_bytes)],
    ['Bits/point', formatFixed(d.bits_per_point, 2)],
    ['vs Draco', d.draco ? `${formatDracoRatio(d)} (Draco ${formatFixed(d.draco.bits_per_point, 2)} bits/point)` : '–'],
  ];
}

export class DatasetPage {
  constructor(root, api, id, kind, params) {
    Object.assign(this, { api, id, kind, params });
    this.viewport = h('div.viewport#viewport');
    this.hud = new Hud();
    this.title = h('span.title', {}, id);
    this.fitButton = h('button#fit', { type: 'button', disabled: true }, 'Fit');
    this.tools = h('span.tools');
    this.message = h('p.error.fatal#viewer-error', { role: 'alert', hidden: true });
    const base = `/datasets/${encodeURIComponent(id)}`;
    const tab = (href, label, active) => h(active ? 'a.tab.active' : 'a.tab', { href }, label);
    root.replaceChildren(
      h('header.top.overlay', {},
        h('h1', {}, h('a', { href: '/' }, 'pointdag')), this.title,
        h('nav', {}, tab(base, 'pdag tiles', kind === 'pdag'), tab(`${base}/3dtiles`, '3D Tiles', kind === '3dtiles')),
        this.tools, this.fitButton),
      h('main.dataset', {}, this.viewport, this.hud.element, this.message));
  }

  async start() {
    try {
      // The metadata and the viewer's code load side by side.
      const [dataset, { SceneView, UP_AXES }, Viewer] = await Promise.all([
        this.api.dataset(this.id), import('../viewer/scene_view.js'), this.viewerClass()]);
      this.title.textContent = dataset.name;
      document.title = `${dataset.name} · pointdag`;
      this.hud.setMeta(metaRows(dataset));
      const up = new UpAxisSelect(this.id, UP_AXES, this.params);
      // .pdag tiles decode to sRGB bytes; 3D Tiles carry linear colors (glTF's COLOR_0).
      const view = new SceneView(this.viewport, up.axis, { srgbColors: this.kind === 'pdag' });
      const viewer = new Viewer(view, this.api, dataset, this.params);
      up.onChange = (axis) => {
        view.setUpAxis(axis);
        viewer.upAxisChanged(); // tiles colored by height
        viewer.fit();
      };
      this.tools.append(up.element);
      window.pointdagViewer = { state: () => viewer.state(), projectedBounds: () => viewer.projectedBounds() };
      if (dataset.shadows && viewer.setShadows) this.addShadowToggle(dataset.shadows, viewer);
      this.fitButton.addEventListener('click', () => viewer.fit());
      this.fitButton.disabled = false;
      setInterval(() => this.hud.setStats(viewer.statRows()), HUD_MS);
      await viewer.start();
    } catch (err) {
      this.message.hidden = false;
      this.message.textContent = `Cannot show dataset ${this.id}: ${err.message}`;
      console.error(err);
    }
    return this;
  }

  addShadowToggle(shadows, viewer) {
    const toggle = new ShadowToggle(shadows, viewer.shadowAmbient, this.params.get('shadows') === '1', (on) => viewer.setShadows(on));
    this.tools.append(toggle.element);
    if (toggle.legend) this.viewport.after(toggle.legend.element);
    window.pointdagViewer.shadowProbe = (limit) => viewer.shadowProbe(limit);
  }

  async viewerClass() {
    if (this.kind === '3dtiles') return (await import('../viewer/tiles3d_viewer.js')).Tiles3dViewer;
    return (await import('../viewer/pdag_viewer.js')).PdagViewer;
  }
}
