// A refused upload shows the daemon's own error text on the home page: a wrong token (401, and the
// token field asks for attention), a file that is no scan (415), a truncated LAS (400).
import assert from 'node:assert/strict';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';
import { scan } from '../web/lib/config.mjs';
import { openSession } from './browser.mjs';

const TOKEN = 'browser-test-write-token';
let session;
let daemon;
let page;
let dir;

before(async () => {
  dir = mkdtempSync(join(tmpdir(), 'pointdag-refusals-'));
  session = await openSession({ token: TOKEN });
  ({ daemon, page } = session);
});

after(async () => {
  if (session) await session.close();
  if (dir) rmSync(dir, { recursive: true, force: true });
});

// What the daemon answers to the same upload, asked directly.
async function refusal(bytes, token) {
  const res = await fetch(`${daemon.url}/v1/datasets?name=refused`, {
    method: 'POST', body: bytes, headers: { Authorization: `Bearer ${token}` },
  });
  return { status: res.status, error: (await res.json()).error };
}

async function uploadThroughPage(file, token) {
  await page.goto(`${daemon.url}/`);
  await page.locator('#token').fill(token);
  await page.locator('#token').blur();
  await page.locator('#file').setInputFiles(file);
  await page.locator('#name').fill('refused');
  await page.locator('#upload').click();
  const error = page.locator('#upload-error');
  await error.waitFor({ state: 'visible', timeout: 30_000 });
  return error.textContent();
}

const tiny = scan('tiny_1.2-with-color_1065pts.las');
const cases = [
  { what: 'a wrong token', status: 401, token: 'not-the-token', file: () => tiny },
  { what: 'a text file', status: 415, token: TOKEN, file: () => {
    const path = join(dir, 'notes.las');
    writeFileSync(path, 'these are notes, not a scan\n');
    return path;
  } },
  { what: 'a truncated LAS', status: 400, token: TOKEN, file: () => {
    const path = join(dir, 'truncated.las');
    writeFileSync(path, readFileSync(tiny).subarray(0, 3000));
    return path;
  } },
];

for (const c of cases) {
  test(`an upload of ${c.what} shows the daemon's ${c.status} error text`, async () => {
    const file = c.file();
    const expected = await refusal(readFileSync(file), c.token);
    assert.equal(expected.status, c.status);
    assert.ok(expected.error.length > 0);
    assert.equal(await uploadThroughPage(file, c.token), `Refused (${c.status}): ${expected.error}`);
    if (c.status === 401) assert.equal(await page.locator('form.token').getAttribute('class'), 'card token attention');
    assert.equal(await page.locator('#job-status').textContent(), 'not started');
    assert.equal(await page.locator('#dataset-link').count(), 0);
  });
}
