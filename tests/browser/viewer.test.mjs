// Through the pages in a real Chromium against a real pointdagd: upload a scan on the home page,
// follow its job to a link, then see the dataset drawn from our .pdag tiles and from its 3D Tiles.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { scan } from '../web/lib/config.mjs';
import { ingest } from '../web/lib/pointdagd.mjs';
import { openSession } from './browser.mjs';
import { checkDrawn } from './drawn_check.mjs';
import { foregroundMean, foregroundShare, intersectionOverUnion } from './screenshot_check.mjs';

const TOKEN = 'browser-test-write-token';
const NAME = 'autzen-browser';
let session;
let daemon;
let page;
let datasetPath = null;
let pdagDrawn = null; // what the .pdag page showed, for the 3D Tiles page to match

before(async () => {
  session = await openSession({ token: TOKEN });
  ({ daemon, page } = session);
});

after(async () => {
  if (session) await session.close();
});

test('a scan uploaded on the home page, with the token, becomes a linked dataset', async () => {
  await page.goto(`${daemon.url}/`);
  await page.locator('#token').fill(TOKEN);
  await page.locator('#token').blur();
  await page.locator('#file').setInputFiles(scan('autzen_trim_pdrf3_rgb.las'));
  await page.locator('#name').fill(NAME);
  await page.locator('#upload').click();
  const link = page.locator('#dataset-link');
  await link.waitFor({ state: 'visible', timeout: 120_000 });
  assert.equal(await page.locator('#send-progress').evaluate((p) => p.value / p.max), 1);
  assert.equal(await page.locator('#job-progress').evaluate((p) => p.value), 100);
  assert.match(await page.locator('#job-status').textContent(), /^done/);
  assert.equal(await page.locator('#upload-error').isHidden(), true);
  assert.equal(await page.evaluate(() => localStorage.getItem('pointdag.token')), TOKEN);
  datasetPath = new URL(await link.getAttribute('href'), daemon.url).pathname;
  assert.match(datasetPath, /^\/datasets\/[0-9a-f]+$/);
  // The list refreshed: the new dataset is linked with its sizes.
  const row = page.locator('#datasets tr', { has: page.locator(`a[href="${datasetPath}"]`) });
  await row.waitFor({ timeout: 10_000 });
  const cells = await row.locator('td').allTextContents();
  const dataset = await (await fetch(`${daemon.url}/v1${datasetPath}`)).json();
  assert.equal(cells[0], NAME);
  assert.equal(cells[1], '110,000');
  assert.equal(cells[2], dataset.voxels.toLocaleString('en-US'));
  assert.equal(cells[4], dataset.bits_per_point.toFixed(2));
  assert.ok(dataset.draco.draco_over_ours > 1); // Autzen: Draco's bits over ours
  assert.equal(cells[5], `${dataset.draco.draco_over_ours.toFixed(2)}× smaller`);
  assert.deepEqual(page.errors, []);
});

test('the dataset page draws the scan from .pdag tiles where its bounds project', async (t) => {
  assert.ok(datasetPath, 'the upload test made no dataset');
  // A shareable URL, loaded directly; hierarchy pages of one level, so that the viewer walks pages.
  await page.goto(`${daemon.url}${datasetPath}?pagedepth=1`);
  pdagDrawn = await checkDrawn(page, 'pdag', t);
  const { state } = pdagDrawn;
  t.diagnostic(`decoded ${state.decoder.tiles} tiles with ${state.decoder.backend} in ${state.decoder.ms.toFixed(0)} ms`);
  assert.ok(state.bytesFetched > 0 && state.decoder.tiles > 0, JSON.stringify(state));
  assert.match(state.decoder.backend, /^(js|wasm)$/);
  // The root's page, then one for each of Autzen's two level-1 tiles, whose children the view needs.
  assert.equal(state.hierarchyPages, 3);
  assert.equal(state.errors, 0);
  assert.deepEqual(page.errors, []);
});

test('the 3D Tiles page draws the same scan with 3d-tiles-renderer', async (t) => {
  assert.ok(datasetPath, 'the upload test made no dataset');
  await page.goto(`${daemon.url}${datasetPath}/3dtiles`);
  const drawn = await checkDrawn(page, '3dtiles', t);
  // The same voxels in the same frame and view: the same levels, and the scan where the .pdag page drew it.
  assert.ok(pdagDrawn, 'the .pdag page drew nothing to compare with');
  assert.deepEqual(drawn.state.levelsDrawn, pdagDrawn.state.levelsDrawn);
  assert.equal(drawn.state.pointsOnScreen, pdagDrawn.state.pointsOnScreen);
  const iou = intersectionOverUnion(drawn.fg.box, pdagDrawn.fg.box);
  assert.ok(iou >= 0.9, `the 3D Tiles page drew the scan at ${JSON.stringify(drawn.fg.box)}, the .pdag page at ${JSON.stringify(pdagDrawn.fg.box)}`);
  // In the same colors: the .pdag page draws the tiles' sRGB bytes as they are, the 3D Tiles page
  // glTF's linear COLOR_0 converted back to sRGB on output.
  const [ours, theirs] = [foregroundMean(pdagDrawn.png), foregroundMean(drawn.png)];
  t.diagnostic(`mean color: .pdag page ${ours.map((v) => v.toFixed(1))}, 3D Tiles page ${theirs.map((v) => v.toFixed(1))}`);
  for (let c = 0; c < 3; ++c) assert.ok(Math.abs(ours[c] - theirs[c]) < 2, `mean colors ${ours} and ${theirs}`);
  assert.deepEqual(page.errors, []);
});

test('the dataset page keeps its budget of resident points, unloading what the view left', async (t) => {
  assert.ok(datasetPath, 'the upload test made no dataset');
  // Below what Autzen's full view wants (its finest level alone is ~99k voxels, root and level 1
  // together ~66k): the fitted view stays at level 0, a zoom into one end refines there.
  const budget = 60_000;
  await page.goto(`${daemon.url}${datasetPath}?budget=${budget}`);
  // Settled: the view complete and unchanged over 300 ms (the controls' damping has stopped and
  // no tile arrived meanwhile).
  const settled = async () => {
    const snapshot = () => page.evaluate(() => window.pointdagViewer?.state());
    const key = (st) => JSON.stringify([st.levelsDrawn, st.tilesOnScreen, st.pointsOnScreen, st.tilesFetched]);
    const deadline = Date.now() + 60_000;
    for (;;) {
      const before = await snapshot();
      await page.waitForTimeout(300);
      const after = await snapshot();
      if (before?.finestVisibleLevelDrawn && after?.finestVisibleLevelDrawn && key(before) === key(after)) return after;
      assert.ok(Date.now() < deadline, `the view did not settle in 60 s: ${JSON.stringify(after)}`);
    }
  };
  const box = await page.locator('canvas').boundingBox();
  // Zoom in with the wheel over a point of the scan (clear of the HUD, which takes the wheel there).
  const zoomInAt = async (fx, fy, steps) => {
    await page.mouse.move(box.x + box.width * fx, box.y + box.height * fy);
    for (let i = 0; i < steps; ++i) await page.mouse.wheel(0, -300);
    return settled();
  };
  const fit = async () => {
    await page.locator('#fit').click();
    return settled();
  };
  const states = { fitted: await settled() };
  assert.equal(states.fitted.budgetPoints, budget);
  states.zoomedEast = await zoomInAt(0.8, 0.48, 20);
  states.refitted = await fit();
  states.zoomedWest = await zoomInAt(0.3, 0.78, 12);
  const s = states;
  t.diagnostic(Object.entries(s).map(([k, v]) => `${k}: levels ${v.levelsDrawn.join(',')}, ${v.pointsOnScreen} on screen, ` +
    `${v.residentPoints} resident`).join('; ') + `; ${s.zoomedWest.decoder.voxels} decoded in all, ${s.zoomedWest.evictedTiles} tiles evicted`);
  for (const [k, v] of Object.entries(s)) {
    assert.ok(v.residentPoints <= budget, `${k}: resident ${v.residentPoints} > budget ${budget}`);
    assert.ok(v.pointsOnScreen > 0, `${k}: nothing drawn`);
  }
  // The zooms refined past the coarse view as far as the budget allows.
  assert.deepEqual(s.fitted.levelsDrawn, [0]);
  for (const k of ['zoomedEast', 'zoomedWest']) {
    assert.ok(Math.min(...s[k].levelsDrawn) > 0, `${k}: still drawing levels ${s[k].levelsDrawn}`);
  }
  // More was decoded than the budget holds, and resident stayed within it: tiles were unloaded.
  assert.ok(s.zoomedWest.decoder.voxels > budget, `decoded only ${s.zoomedWest.decoder.voxels} voxels: the zooms loaded nothing new`);
  assert.ok(s.zoomedWest.evictedTiles > 0);
  assert.deepEqual(page.errors, []);
});

test('a statue scanned with Y up stands upright when the page is told so, and the page remembers it', async (t) => {
  // Guanyin (a photogrammetry statue, Y up in its PLY): lying on its side with Z up, standing with Y up.
  const id = await ingest(daemon.url, scan('pcx_guanyin_cc-by-4.0_rgb.ply'), { name: 'guanyin-up', token: TOKEN });
  const path = `/datasets/${id}`;
  const aspect = (b) => (b.y1 - b.y0) / (b.x1 - b.x0);
  await page.goto(`${daemon.url}${path}`);
  assert.equal(await page.locator('#up-axis').inputValue(), 'z');
  await page.locator('#up-axis').selectOption('y');
  assert.equal(await page.evaluate((key) => localStorage.getItem(key), `pointdag.up.${id}`), 'y');
  // Drawn and screenshot after a reload, which keeps the choice (checkDrawn hides the top bar).
  await page.goto(`${daemon.url}${path}`);
  assert.equal(await page.locator('#up-axis').inputValue(), 'y');
  const statue = { minIou: 0.3 };
  const y = await checkDrawn(page, 'guanyin-up-y', t, statue);
  // The URL's choice wins over the remembered one.
  await page.goto(`${daemon.url}${path}?up=z`);
  assert.equal(await page.locator('#up-axis').inputValue(), 'z');
  const z = await checkDrawn(page, 'guanyin-up-z', t, statue);
  t.diagnostic(`drawn aspect (height / width): Z up ${aspect(z.fg.box).toFixed(2)}, Y up ${aspect(y.fg.box).toFixed(2)}`);
  assert.ok(aspect(y.fg.box) > 1.2, `Y up: the statue does not stand: ${JSON.stringify(y.fg.box)}`);
  assert.ok(aspect(y.fg.box) > 1.25 * aspect(z.fg.box), `Z up ${JSON.stringify(z.fg.box)}, Y up ${JSON.stringify(y.fg.box)}`);
  // The 3D Tiles page follows the remembered choice.
  await page.goto(`${daemon.url}${path}/3dtiles`);
  assert.equal(await page.locator('#up-axis').inputValue(), 'y');
  const tiles = await checkDrawn(page, 'guanyin-3dtiles-up-y', t, statue);
  assert.ok(intersectionOverUnion(tiles.fg.box, y.fg.box) >= 0.9, `3D Tiles ${JSON.stringify(tiles.fg.box)}, pdag ${JSON.stringify(y.fg.box)}`);
  assert.deepEqual(page.errors, []);
});

test('a scan without color is drawn by height, low violet to high yellow, along the chosen up axis', async (t) => {
  // (its LAS names a geocentric CRS for UTM 12N coordinates: the upload says which)
  const id = await ingest(daemon.url, scan('lone_star_tls_noRGB.las'), { name: 'lone-star', token: TOKEN, epsg: 26912 });
  await page.goto(`${daemon.url}/datasets/${id}?up=z`);
  const drawn = await checkDrawn(page, 'lone-star-height', t, { minIou: 0.3 });
  const { png } = drawn;
  // The ramp's low end is blue over green (violet, 68 1 84), its high end green well over blue
  // (yellow-green, 94 201 98 and 253 231 37); the old flat grey (200 204 212) is neither.
  const low = foregroundShare(png, ([, g, b]) => b > g + 20);
  const high = foregroundShare(png, ([, g, b]) => g > b + 40);
  t.diagnostic(`foreground ${(drawn.fg.share * 100).toFixed(1)}% of the canvas: ${(low * 100).toFixed(1)}% low colors, ${(high * 100).toFixed(1)}% high`);
  assert.ok(low > 0.05 && high > 0.05, `low ${low}, high ${high}`);
  // The 3D Tiles page colors it alike (in linear colors, as its glTF are).
  await page.goto(`${daemon.url}/datasets/${id}/3dtiles?up=z`);
  const tiles = await checkDrawn(page, 'lone-star-height-3dtiles', t, { minIou: 0.3 });
  const [ours, theirs] = [foregroundMean(png), foregroundMean(tiles.png)];
  t.diagnostic(`mean color: .pdag page ${ours.map((v) => v.toFixed(1))}, 3D Tiles page ${theirs.map((v) => v.toFixed(1))}`);
  for (let c = 0; c < 3; ++c) assert.ok(Math.abs(ours[c] - theirs[c]) < 3, `mean colors ${ours} and ${theirs}`);
  assert.deepEqual(page.errors, []);
});
