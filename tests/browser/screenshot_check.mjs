// What a screenshot shows: the pixels that differ from the scene's background, and their bounding box.
import { requireWebModule } from './browser.mjs';

// Background of the scene (web/src/viewer/scene_view.js BACKGROUND).
export const BACKGROUND = [0x1b, 0x22, 0x30];

// {share, box: {x0, y0, x1, y1} | null} of the pixels whose channels differ from the background
// by more than `tolerance` in any channel; x1/y1 are exclusive.
export function foreground(png, tolerance = 12) {
  const { PNG } = requireWebModule('pngjs');
  const { width, height, data } = PNG.sync.read(png);
  let count = 0;
  const box = { x0: width, y0: height, x1: 0, y1: 0 };
  for (let y = 0; y < height; ++y) {
    for (let x = 0; x < width; ++x) {
      const i = 4 * (y * width + x);
      if (Math.abs(data[i] - BACKGROUND[0]) <= tolerance && Math.abs(data[i + 1] - BACKGROUND[1]) <= tolerance &&
          Math.abs(data[i + 2] - BACKGROUND[2]) <= tolerance) continue;
      count++;
      box.x0 = Math.min(box.x0, x);
      box.y0 = Math.min(box.y0, y);
      box.x1 = Math.max(box.x1, x + 1);
      box.y1 = Math.max(box.y1, y + 1);
    }
  }
  return { width, height, share: count / (width * height), box: count ? box : null };
}

// The share of the foreground pixels (as foreground() finds them) whose [r, g, b] pass `predicate`.
export function foregroundShare(png, predicate, tolerance = 12) {
  const { PNG } = requireWebModule('pngjs');
  const { width, height, data } = PNG.sync.read(png);
  let all = 0;
  let passing = 0;
  for (let i = 0; i < 4 * width * height; i += 4) {
    const rgb = [data[i], data[i + 1], data[i + 2]];
    if (rgb.every((v, c) => Math.abs(v - BACKGROUND[c]) <= tolerance)) continue;
    all++;
    if (predicate(rgb)) passing++;
  }
  return all ? passing / all : 0;
}

// The mean [r, g, b] of the foreground pixels.
export function foregroundMean(png, tolerance = 12) {
  const { PNG } = requireWebModule('pngjs');
  const { width, height, data } = PNG.sync.read(png);
  const sum = [0, 0, 0];
  let n = 0;
  for (let i = 0; i < 4 * width * height; i += 4) {
    if ([0, 1, 2].every((c) => Math.abs(data[i + c] - BACKGROUND[c]) <= tolerance)) continue;
    for (let c = 0; c < 3; ++c) sum[c] += data[i + c];
    n++;
  }
  return sum.map((v) => v / Math.max(n, 1));
}

function area(r) {
  return Math.max(0, r.x1 - r.x0) * Math.max(0, r.y1 - r.y0);
}

export function clip(r, width, height) {
  return { x0: Math.max(0, r.x0), y0: Math.max(0, r.y0), x1: Math.min(width, r.x1), y1: Math.min(height, r.y1) };
}

export function intersectionOverUnion(a, b) {
  const inter = area({ x0: Math.max(a.x0, b.x0), y0: Math.max(a.y0, b.y0), x1: Math.min(a.x1, b.x1), y1: Math.min(a.y1, b.y1) });
  return inter / (area(a) + area(b) - inter);
}

// True when `inner` lies inside `outer` grown by `margin` pixels on every side.
export function containedIn(inner, outer, margin) {
  return inner.x0 >= outer.x0 - margin && inner.y0 >= outer.y0 - margin &&
    inner.x1 <= outer.x1 + margin && inner.y1 <= outer.y1 + margin;
}
