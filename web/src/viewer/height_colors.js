// Scans without color (many LIDAR and terrestrial scans) drawn by height: each point takes a color
// from a viridis-like ramp by its height along the view's up axis (scene_view.js UP_AXES) across the
// heights of the first tile drawn (the root: every part of the scan, coarsely), from its 1st to its
// 99th percentile (a few stray points far above or below would squeeze the rest into one color), so
// that ground, buildings and trees read apart instead of one grey.
// The colors are a per-point attribute, like a colored scan's: shadow shading applies to them alike,
// and a new up axis repaints the resident tiles.
import * as THREE from 'three';

// Viridis from a tenth up (its darkest violet is lost on the dark background), low to high.
const STOPS = [[72, 40, 120], [49, 104, 142], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
const RAMP = (() => {
  const ramp = new Uint8Array(256 * 3);
  for (let i = 0; i < 256; ++i) {
    const x = (i / 255) * (STOPS.length - 1);
    const k = Math.min(Math.floor(x), STOPS.length - 2);
    const f = x - k;
    for (let c = 0; c < 3; ++c) ramp[3 * i + c] = Math.round(STOPS[k][c] * (1 - f) + STOPS[k + 1][c] * f);
  }
  return ramp;
})();

// Per up axis: the frame's component that is height, and its sign.
const HEIGHT_OF = { z: [2, 1], y: [1, 1], '-y': [1, -1] };

// The 1st and 99th percentile of the heights of `points` (tile_points.js) along `axis`.
export function heightRange(points, axis) {
  const [k, sign] = HEIGHT_OF[axis];
  const cells = points.geometry.getAttribute('position').array;
  const n = cells.length / 3;
  const heights = new Float64Array(n);
  const base = sign * points.position.getComponent(k);
  const step = sign * points.scale.x;
  for (let i = 0; i < n; ++i) heights[i] = base + step * cells[3 * i + k];
  heights.sort();
  return n ? [heights[Math.floor(0.01 * (n - 1))], heights[Math.ceil(0.99 * (n - 1))]] : [0, 1];
}

// Colors `points` (tile_points.js: integer cells scaled and placed by the object's matrix) by height.
export function paintByHeight(points, axis, [lo, hi]) {
  const [k, sign] = HEIGHT_OF[axis];
  const cells = points.geometry.getAttribute('position').array;
  const n = cells.length / 3;
  let colors = points.geometry.getAttribute('color');
  if (!colors) {
    colors = new THREE.BufferAttribute(new Uint8Array(3 * n), 3, true);
    points.geometry.setAttribute('color', colors);
  }
  const out = colors.array;
  const base = sign * points.position.getComponent(k);
  const step = sign * points.scale.x;
  const scale = 255 / Math.max(hi - lo, 1e-9);
  for (let i = 0; i < n; ++i) {
    const t = Math.round((base + step * cells[3 * i + k] - lo) * scale);
    const j = 3 * (t < 0 ? 0 : t > 255 ? 255 : t);
    out[3 * i] = RAMP[j];
    out[3 * i + 1] = RAMP[j + 1];
    out[3 * i + 2] = RAMP[j + 2];
  }
  colors.needsUpdate = true;
}
