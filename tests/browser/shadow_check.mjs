// What the shadow toggle must do to the pixels: screenshots of the scene (overlays hidden) with the
// shading off and on, compared where the viewer's probe says its voxels land (their light from the
// shadow layer). The viewer multiplies a voxel's displayed colour by ambient + (1 - ambient) * light/255.
import assert from 'node:assert/strict';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { decodeShadowLayer } from '../../web/src/decoder/shadow_layer.js';
import { listTiles } from '../web/lib/pointdagd.mjs';
import { requireWebModule } from './browser.mjs';
import { BACKGROUND } from './screenshot_check.mjs';

export const AMBIENT = 0.35; // web/src/viewer/shadow_shading.js SHADOW_AMBIENT

const luminance = (d, i) => 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
const isBackground = (d, i) => [0, 1, 2].every((c) => Math.abs(d[i + c] - BACKGROUND[c]) <= 12);

// The scene alone: header, HUD and legend hidden (they are overlays on the canvas).
export async function sceneShot(page, name) {
  const hide = await page.addStyleTag({ content: 'header.top, .hud, .shadow-legend { visibility: hidden !important; }' });
  const png = await page.screenshot();
  await hide.evaluate((style) => style.remove()); // the toggle must stay clickable
  if (process.env.POINTDAG_SCREENSHOT_DIR) writeFileSync(join(process.env.POINTDAG_SCREENSHOT_DIR, `${name}.png`), png);
  return requireWebModule('pngjs').PNG.sync.read(png);
}

// The viewer's probe of visible voxels ({x, y, tile, index}), each with its light as the daemon's
// layer of its tile says (fetched and decoded here, not taken from the page).
export async function probeWithLight(page, baseUrl, datasetId, limit) {
  const probe = await page.evaluate((n) => window.pointdagViewer.shadowProbe(n), limit);
  const voxels = new Map((await listTiles(baseUrl, datasetId)).map((t) => [`${t.level}/${t.x}/${t.y}/${t.z}`, t.voxels]));
  const layers = new Map();
  for (const tile of new Set(probe.map((p) => p.tile))) {
    const r = await fetch(`${baseUrl}/v1/datasets/${datasetId}/shadows/tiles/${tile}`);
    assert.equal(r.status, 200, `layer ${tile}`);
    layers.set(tile, decodeShadowLayer(new Uint8Array(await r.arrayBuffer()), voxels.get(tile)).light);
  }
  return probe.map((p) => ({ ...p, light: layers.get(p.tile)[p.index] }));
}

// Waits until the view is complete and every drawn tile has its layer settled (shaded or missing);
// returns the viewer's state.
export async function waitShadowsSettled(page) {
  await page.waitForFunction(() => {
    const s = window.pointdagViewer?.state();
    return s && s.finestVisibleLevelDrawn && s.shadows && s.shadows.loading === 0 &&
      s.shadows.tilesShaded + s.shadows.tilesWithoutLayer === s.tilesOnScreen;
  }, null, { timeout: 60_000, polling: 100 });
  return page.evaluate(() => window.pointdagViewer.state());
}

// Toggles the page's Shadows checkbox to `on` and waits for the frame that shows it.
export async function setShadows(page, on) {
  await page.locator('#shadows').setChecked(on);
  // The render loop draws on the next animation frame: two frames later it has.
  await page.evaluate(() => new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve))));
}

function median(values) {
  const s = [...values].sort((a, b) => a - b);
  return s.length ? s[s.length >> 1] : NaN;
}

// Off and on: the same frame but for the shading. Returns the measures: pixels the shading made
// brighter, the mean luminance of the scan's pixels (not the background) off and on, and at the
// probed voxels' pixels the share whose luminance kept is the factor of their light (within 0.05),
// and the median share kept for shadowed (light 0) and lit (255) voxels.
export function compareShading(off, on, probe) {
  assert.equal(on.width, off.width);
  let brighter = 0;
  let sumOff = 0;
  let sumOn = 0;
  let foreground = 0;
  for (let i = 0; i < off.data.length; i += 4) {
    const a = luminance(off.data, i);
    const b = luminance(on.data, i);
    if (b > a + 2) brighter++;
    if (!isBackground(off.data, i)) {
      foreground++;
      sumOff += a;
      sumOn += b;
    }
  }
  // At each probed voxel's pixel: how much the shading kept of its luminance (well-lit pixels only),
  // and how far that is from the factor its light asks for (a nearer voxel may cover the pixel).
  const ratios = { shadowed: [], lit: [] };
  let matching = 0;
  let measured = 0;
  for (const { x, y, light } of probe) {
    const i = 4 * (Math.floor(y) * off.width + Math.floor(x));
    const a = luminance(off.data, i);
    if (a < 40) continue;
    const kept = luminance(on.data, i) / a;
    measured++;
    if (Math.abs(kept - (AMBIENT + ((1 - AMBIENT) * light) / 255)) < 0.05) matching++;
    if (light === 0) ratios.shadowed.push(kept);
    else if (light === 255) ratios.lit.push(kept);
  }
  return {
    matchingShare: matching / measured,
    brighterPixels: brighter,
    meanOff: sumOff / foreground,
    meanOn: sumOn / foreground,
    shadowedProbes: ratios.shadowed.length,
    litProbes: ratios.lit.length,
    shadowedKept: median(ratios.shadowed),
    litKept: median(ratios.lit),
  };
}

// Pixels that differ between two screenshots by more than `tolerance` in a channel.
export function differingPixels(a, b, tolerance = 1) {
  let n = 0;
  for (let i = 0; i < a.data.length; i += 4) {
    if (Math.abs(a.data[i] - b.data[i]) > tolerance || Math.abs(a.data[i + 1] - b.data[i + 1]) > tolerance ||
        Math.abs(a.data[i + 2] - b.data[i + 2]) > tolerance) n++;
  }
  return n;
}
