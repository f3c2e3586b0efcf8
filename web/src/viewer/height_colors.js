// Scans without color (many LIDAR and terrestrial scans) drawn by height: each point takes a color
// from a viridis-like ramp by its height along the view's up axis (scene_view.js UP_AXES) across the
// heights of the first tile drawn (the root: every part of the scan, coarsely), from its 1st to its
// 99th percentile (a few stray points far above or below would squeeze the rest into one color), so
// that ground, buildings and trees read apart instead of one grey.
// The colors are a per-point attribute, like a colored scan's: shadow shading applies to them alike,
// and a new up axis repaints the resident tiles. `matrix` (THREE.Matrix4) maps the points' position
// attribute into the viewer's frame; `linear`: 16-bit linear colors (a glTF page's, converted to sRGB on
// output) instead of the sRGB bytes the .pdag page draws as they are.
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

const RAMP_LINEAR = Uint16Array.from(RAMP, (v) => {
  const c = v / 255;
  return Math.round(65535 * (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4));
});

// Per up axis: the frame's component that is height, and its sign.
const HEIGHT_OF = { z: [2, 1], y: [1, 1], '-y': [1, -1] };

// Height of point i: the matrix's row of that component applied to the cell, signed.
function heightsOf(points, matrix, axis, visit) {
  const [k, sign] = HEIGHT_OF[axis];
  const e = matrix.elements;
  const [ax, ay, az, at] = [e[k], e[4 + k], e[8 + k], e[12 + k]].map((v) => sign * v);
  const cells = points.geometry.getAttribute('position');
  if (!cells.isInterleavedBufferAttribute && !cells.normalized) {  // .pdag tiles: packed x, y, z
    const a = cells.array;
    for (let i = 0; i < cells.count; ++i) visit(i, ax * a[3 * i] + ay * a[3 * i + 1] + az * a[3 * i + 2] + at);
    return;
  }
  // glTF's may be strided (8-byte u16 cells): read through the attribute.
  for (let i = 0; i < cells.count; ++i) visit(i, ax * cells.getX(i) + ay * cells.getY(i) + az * cells.getZ(i) + at);
}

// The 1st and 99th percentile of the heights of `points` along `axis`.
export function heightRange(points, matrix, axis) {
  const heights = new Float64Array(points.geometry.getAttribute('position').count);
  heightsOf(points, matrix, axis, (i, h) => { heights[i] = h; });
  heights.sort();
  const n = heights.length;
  return n ? [heights[Math.floor(0.01 * (n - 1))], heights[Math.ceil(0.99 * (n - 1))]] : [0, 1];
}

// Colors `points` by height.
export function paintByHeight(points, matrix, axis, [lo, hi], { linear = false } = {}) {
  const n = points.geometry.getAttribute('position').count;
  let colors = points.geometry.getAttribute('color');
  if (!colors) {
    colors = new THREE.BufferAttribute(linear ? new Uint16Array(3 * n) : new Uint8Array(3 * n), 3, true);
    points.geometry.setAttribute('color', colors);
  }
  const out = colors.array;
  const ramp = linear ? RAMP_LINEAR : RAMP;
  const scale = 255 / Math.max(hi - lo, 1e-9);
  heightsOf(points, matrix, axis, (i, h) => {
    const t = Math.round((h - lo) * scale);
    const j = 3 * (t < 0 ? 0 : t > 255 ? 255 : t);
    out[3 * i] = ramp[j];
    out[3 * i + 1] = ramp[j + 1];
    out[3 * i + 2] = ramp[j + 2];
  });
  colors.needsUpdate = true;
}
