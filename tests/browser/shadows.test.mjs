// The Shadows toggle in a real Chromium against a real pointdagd: a dataset without shadows shows no
// toggle; after a shadow job (a light direction) its page has one, and turning it on darkens the
// pixels of the voxels its layers call shadowed to the ambient share, leaves lit ones as they were,
// and lowers the scan's mean luminance; turning it off gives back the unshaded pixels, with no tile
// or layer fetched again. The 3D Tiles page does the same.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { scan } from '../web/lib/config.mjs';
import { computeShadows, ingest } from '../web/lib/pointdagd.mjs';
import { openSession } from './browser.mjs';
import { checkDrawn } from './drawn_check.mjs';
import { AMBIENT, compareShading, differingPixels, probeWithLight, sceneShot, setShadows, waitShadowsSettled } from './shadow_check.mjs';

// From above at 56 degrees (steeper than 45: flat ground does not shadow itself at voxel scale),
// so that Autzen's trees and buildings cast shadows on the ground beside lit ground.
const DIRECTION = [0.6, 0.3, -1];
const PROBES = 4000;

let session;
let daemon;
let page;
let datasetId = null;
let shadows = null; // the dataset's `shadows` after the job

// The view complete (checkDrawn's checks ran on the same view in the first test; it hides the top
// bar, which holds the toggle).
async function waitComplete(page) {
  await page.waitForFunction(() => {
    const s = window.pointdagViewer?.state();
    return s && s.finestVisibleLevelDrawn && s.loading === 0;
  }, null, { timeout: 60_000, polling: 100 });
}

before(async () => {
  session = await openSession();
  ({ daemon, page } = session);
  datasetId = await ingest(daemon.url, scan('autzen_trim_pdrf3_rgb.las'), { name: 'autzen-shadows' });
});

after(async () => {
  if (session) await session.close();
});

test('a dataset without shadows has no Shadows toggle', async (t) => {
  await page.goto(`${daemon.url}/datasets/${datasetId}`);
  await checkDrawn(page, 'shadows-none', t);
  assert.equal(await page.locator('#shadows').count(), 0);
  assert.equal(await page.locator('#shadow-legend').count(), 0);
  assert.deepEqual(page.errors, []);
});

// On the page just opened (toggle off): turns shadows on and checks the pixels against the layers.
// Returns the screenshots and states off and on.
async function turnOnAndCheck(page, name, t) {
  await waitComplete(page);
  assert.equal(await page.locator('#shadows').isChecked(), false);
  const off = await sceneShot(page, `${name}-off`);
  const before = await page.evaluate(() => window.pointdagViewer.state());
  assert.equal(before.shadows.bytesFetched, 0, 'layers fetched before the toggle was turned on');

  await setShadows(page, true);
  const on = await waitShadowsSettled(page);
  assert.equal(on.shadows.tilesShaded, on.tilesOnScreen, JSON.stringify(on.shadows));
  assert.equal(on.shadows.errors, 0, on.shadows.lastError);
  assert.equal(on.shadows.missing, 0);
  assert.equal(on.tilesFetched, before.tilesFetched, 'turning shadows on fetched tiles again');
  const onShot = await sceneShot(page, `${name}-on`);
  const probe = await probeWithLight(page, daemon.url, datasetId, PROBES);
  const m = compareShading(off, onShot, probe);
  const shadowedShare = probe.filter((p) => p.light === 0).length / probe.length;
  t.diagnostic(`${name}: ${probe.length} probed voxels, ${(shadowedShare * 100).toFixed(1)}% shadowed; ${JSON.stringify(m)}; ` +
    `${on.shadows.bytesFetched} layer bytes fetched, ${on.tilesOnScreen} tiles on screen`);
  // Nearly every probed voxel's pixel is its colour times the factor of its light (the others are
  // covered by a nearer voxel).
  assert.ok(m.matchingShare > 0.9, `only ${m.matchingShare} of the probed pixels have their voxel's shading`);
  assert.equal(m.brighterPixels, 0, 'the shading brightened pixels');
  // The scan as a whole darker: by at least a quarter of what its voxels' light implies (shadowed
  // voxels are hidden more often than lit ones: under the canopy that shadows them).
  const drop = probe.reduce((sum, p) => sum + (1 - AMBIENT) * (1 - p.light / 255), 0) / probe.length;
  assert.ok(m.meanOn < m.meanOff * (1 - drop / 4), `mean luminance ${m.meanOff} -> ${m.meanOn}, expected drop ${drop}`);
  return { off, onShot, on, m, shadowedShare };
}

test('after a shadow job the page shades shadowed voxels when the toggle is on, and only then', async (t) => {
  const dataset = await computeShadows(daemon.url, datasetId, { direction: DIRECTION });
  shadows = dataset.shadows;
  assert.ok(shadows, `no shadows in the metadata after the job: ${JSON.stringify(dataset)}`);
  await page.goto(`${daemon.url}/datasets/${datasetId}`);
  const { off, onShot, on, m, shadowedShare } = await turnOnAndCheck(page, 'shadows-pdag', t);
  // One direction: shadowed and lit voxels in view; where the layer says shadowed the pixel keeps
  // the ambient share of its luminance, where lit, all of it.
  assert.ok(shadowedShare > 0.05 && shadowedShare < 0.95, `shadowed share ${shadowedShare}`);
  assert.ok(m.shadowedProbes >= 50 && m.litProbes >= 50, JSON.stringify(m));
  assert.ok(Math.abs(m.shadowedKept - AMBIENT) < 0.03, `shadowed voxels kept ${m.shadowedKept} of their luminance`);
  assert.ok(m.litKept > 0.97, `lit voxels kept ${m.litKept} of their luminance`);

  await setShadows(page, false);
  const offAgain = await sceneShot(page, 'shadows-pdag-off-again');
  assert.equal(differingPixels(off, offAgain), 0, 'turned off, the view differs from the unshaded one');
  await setShadows(page, true);
  const again = await page.evaluate(() => window.pointdagViewer.state());
  assert.equal(again.tilesFetched, on.tilesFetched, 'toggling fetched tiles again');
  assert.equal(again.shadows.bytesFetched, on.shadows.bytesFetched, 'toggling fetched layers again');
  assert.equal(differingPixels(onShot, await sceneShot(page, 'shadows-pdag-on-again')), 0);
  assert.deepEqual(page.errors, []);
});

test('the 3D Tiles page shades its points alike', async (t) => {
  assert.ok(shadows, 'the shadow job did not run');
  await page.goto(`${daemon.url}/datasets/${datasetId}/3dtiles`);
  const { off } = await turnOnAndCheck(page, 'shadows-3dtiles', t);
  await setShadows(page, false);
  assert.equal(differingPixels(off, await sceneShot(page, 'shadows-3dtiles-off-again')), 0);
  assert.deepEqual(page.errors, []);
});

test('?shadows=1 opens the page with the shading on', async () => {
  assert.ok(shadows, 'the shadow job did not run');
  await page.goto(`${daemon.url}/datasets/${datasetId}?shadows=1`);
  const state = await waitShadowsSettled(page);
  assert.equal(await page.locator('#shadows').isChecked(), true);
  assert.equal(state.shadows.enabled, true);
  assert.equal(state.shadows.tilesShaded, state.tilesOnScreen);
  // Sun hours only: a legend.
  assert.equal(await page.locator('#shadow-legend').count(), shadows.kind === 'sun_hours' ? 1 : 0);
  assert.deepEqual(page.errors, []);
});

test('a tile whose layer is missing or corrupt is drawn unshaded, and the view stays whole', async () => {
  assert.ok(shadows, 'the shadow job did not run');
  const dataset = await (await fetch(`${daemon.url}/v1/datasets/${datasetId}`)).json();
  // The first two finest-level layers the page asks for: one answered 404, one with a byte flipped.
  let faults = 0;
  await page.route(new RegExp(`/shadows/tiles/${dataset.levels - 1}/`), async (route) => {
    const fault = faults++;
    if (fault === 0) return route.fulfill({ status: 404, contentType: 'application/json', body: '{"error": "no layer"}' });
    if (fault > 1) return route.continue();
    const response = await route.fetch();
    const body = Buffer.from(await response.body());
    body[body.length - 1] ^= 0x40;
    return route.fulfill({ response, body });
  });
  try {
    await page.goto(`${daemon.url}/datasets/${datasetId}?shadows=1`);
    const state = await waitShadowsSettled(page);
    assert.ok(faults >= 2, `only ${faults} finest layers asked for`);
    assert.equal(state.lastError, null, 'a layer broke the view');
    assert.equal(state.errors, 0);
    assert.equal(state.shadows.missing, 1);
    assert.equal(state.shadows.errors, 1);
    assert.match(state.shadows.lastError, /CRC-32C mismatch/);
    assert.equal(state.shadows.tilesWithoutLayer, 2);
    assert.equal(state.shadows.tilesShaded, state.tilesOnScreen - 2);
    // The browser reports the 404 itself; nothing else went wrong.
    assert.deepEqual(page.errors.filter((e) => !/status of 404/.test(e)), []);
    page.errors.length = 0; // the 404 was asked for
  } finally {
    await page.unrouteAll();
  }
});

test('sun hours: the legend shows the span, and each voxel is shaded by its share of the sun', async (t) => {
  assert.ok(shadows, 'the shadow job did not run');
  // Autzen (Oregon, UTC-7) from 08:00 to 18:00 local time on the solstice: 6 suns, 10 hours.
  const dataset = await computeShadows(daemon.url, datasetId, { time: '2024-06-21T15:00:00Z', until: '2024-06-22T01:00:00Z', samples: 6 });
  assert.equal(dataset.shadows.kind, 'sun_hours');
  await page.goto(`${daemon.url}/datasets/${datasetId}`);
  const legend = page.locator('#shadow-legend');
  assert.equal(await legend.isHidden(), true, 'the legend shows while shadows are off');
  const { m } = await turnOnAndCheck(page, 'shadows-sun-hours', t);
  assert.equal(await legend.isVisible(), true);
  assert.match(await legend.textContent(), /Sun hours \(6 samples\).*0 h.*10 h/);
  const lights = new Set((await probeWithLight(page, daemon.url, datasetId, PROBES)).map((p) => p.light));
  assert.ok(lights.size > 2, `only lights ${[...lights]}: sun hours give shares between 0 and 255`);
  await setShadows(page, false);
  assert.equal(await legend.isHidden(), true);
  t.diagnostic(`lights seen: ${[...lights].sort((a, b) => a - b).join(' ')}; ${JSON.stringify(m)}`);
  assert.deepEqual(page.errors, []);
});
