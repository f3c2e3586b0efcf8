// The check both dataset pages pass: once window.pointdagViewer reports the finest visible level
// drawn, a screenshot of the scene (the page's overlays hidden) shows the scan, and where the
// dataset's bounds project.
import assert from 'node:assert/strict';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { clip, containedIn, foreground, intersectionOverUnion } from './screenshot_check.mjs';

const MIN_SHARE = 0.04; // of the canvas's pixels
const MIN_IOU = 0.6;
const MARGIN_PX = 6; // points are squares centred on their voxel: they may stick out of the box by half their width

// t: the node:test context, for a diagnostic line with the measures. minIou: of the drawn pixels' box
// and the projected bounds' (a box seen along a diagonal projects wider than a statue in it).
export async function checkDrawn(page, name, t, { minIou = MIN_IOU } = {}) {
  // Done when drawn, or when the page shows why it cannot draw.
  await page.waitForFunction(() => {
    const viewer = window.pointdagViewer;
    const error = document.querySelector('#viewer-error');
    return (viewer && (viewer.state().finestVisibleLevelDrawn || viewer.state().lastError)) || (error && !error.hidden);
  }, null, { timeout: 60_000, polling: 100 });
  const error = page.locator('#viewer-error');
  assert.ok(await error.isHidden(), `${name}: the page says: ${await error.textContent()}`);
  const { state, bounds } = await page.evaluate(() => ({
    state: window.pointdagViewer.state(), bounds: window.pointdagViewer.projectedBounds(),
  }));
  assert.equal(state.lastError, null, `${name}: ${state.lastError}`);
  assert.ok(state.tilesOnScreen > 0 && state.pointsOnScreen > 0, `${name}: nothing on screen ${JSON.stringify(state)}`);
  assert.ok(state.levelsDrawn.length > 0, `${name}: no level drawn`);
  assert.equal(state.loading, 0, `${name}: still loading`);
  assert.ok(state.firstFrameMs > 0 && state.finestMs >= state.firstFrameMs, `${name}: timings ${JSON.stringify(state)}`);

  await page.addStyleTag({ content: 'header.top, .hud { visibility: hidden !important; }' });
  const png = await page.screenshot();
  if (process.env.POINTDAG_SCREENSHOT_DIR) writeFileSync(join(process.env.POINTDAG_SCREENSHOT_DIR, `${name}.png`), png);
  const fg = foreground(png);
  const expected = clip(bounds, fg.width, fg.height);
  const report = `${name}: foreground ${JSON.stringify(fg.box)} covering ${(fg.share * 100).toFixed(1)}%, projected bounds ${JSON.stringify(bounds)}`;
  assert.ok(fg.share >= MIN_SHARE, `${report}: less than ${MIN_SHARE * 100}% of the canvas differs from the background`);
  assert.ok(containedIn(fg.box, expected, MARGIN_PX), `${report}: points outside the projected bounds`);
  const iou = intersectionOverUnion(fg.box, expected);
  assert.ok(iou >= minIou, `${report}: IoU ${iou.toFixed(3)} < ${minIou}`);
  t.diagnostic(`${report}, IoU ${iou.toFixed(3)}; levels ${state.levelsDrawn}, ${state.tilesOnScreen} tiles, ` +
    `${state.pointsOnScreen} points, first frame ${state.firstFrameMs.toFixed(0)} ms, finest ${state.finestMs.toFixed(0)} ms`);
  return { state, bounds, fg, iou, png };
}
