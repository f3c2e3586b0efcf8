#!/usr/bin/env node
// Benchmark of the web viewer in Chromium (playwright-core, software WebGL) against a running pointdagd:
//   node web/bench/viewer_bench.mjs --url http://127.0.0.1:8080 (--dataset ID | --upload SCAN [--epsg N])
//        [--token T] [--runs 3] [--size 1280x800] [--sse 1.5] [--chromium /usr/bin/chromium]
// For the dataset page (?decoder=js and ?decoder=wasm) and the 3D Tiles page, each run in a fresh
// browser context (empty cache), from navigation to window.pointdagViewer reporting the finest
// visible level drawn: time to the first drawn frame and to the finest level, tile bytes fetched
// (.pdag bodies vs .glb bodies for the same view), and the worker's decode rate (tiles and voxels
// per second of decode time). Prints a Markdown table of the medians.
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { basename } from 'node:path';

const { chromium } = createRequire(import.meta.url)('playwright-core');

const CHROMIUM_ARGS = [
  '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--no-first-run', '--disable-quic',
];

function parseArgs(argv) {
  const opts = { runs: 3, size: '1280x800', sse: null, token: null, chromium: '/usr/bin/chromium' };
  for (let i = 0; i < argv.length; i += 2) {
    const key = argv[i].replace(/^--/, '');
    if (!(key in opts) && !['url', 'dataset', 'upload', 'epsg'].includes(key)) throw new Error(`unknown option ${argv[i]}`);
    opts[key] = argv[i + 1];
  }
  if (!opts.url || !(opts.dataset || opts.upload)) {
    throw new Error('usage: viewer_bench.mjs --url URL (--dataset ID | --upload SCAN [--epsg N]) [--token T] [--runs N] [--size WxH] [--sse PX]');
  }
  opts.runs = Number(opts.runs);
  return opts;
}

async function upload(opts) {
  const params = new URLSearchParams({ name: basename(opts.upload).replace(/\.[^.]*$/, '') });
  if (opts.epsg) params.set('epsg', opts.epsg);
  const headers = opts.token ? { Authorization: `Bearer ${opts.token}` } : {};
  const res = await fetch(`${opts.url}/v1/datasets?${params}`, { method: 'POST', body: readFileSync(opts.upload), headers });
  let job = await res.json();
  if (res.status !== 202) throw new Error(`upload refused (${res.status}): ${job.error}`);
  while (job.status !== 'done') {
    if (job.status === 'failed') throw new Error(`the job failed: ${job.error}`);
    await new Promise((r) => setTimeout(r, 500));
    job = await (await fetch(`${opts.url}/v1/jobs/${job.id}`, { headers })).json();
  }
  return job.dataset_id;
}

// One cold load of `path`; returns the page's state once the finest visible level is drawn.
async function measure(browser, opts, path) {
  const [width, height] = opts.size.split('x').map(Number);
  const context = await browser.newContext({ viewport: { width, height }, deviceScaleFactor: 1 });
  try {
    const page = await context.newPage();
    if (opts.token) await page.addInitScript((t) => localStorage.setItem('pointdag.token', t), opts.token);
    await page.goto(`${opts.url}${path}`);
    await page.waitForFunction(() => {
      const viewer = window.pointdagViewer;
      const error = document.querySelector('#viewer-error');
      return (viewer && (viewer.state().finestVisibleLevelDrawn || viewer.state().lastError)) || (error && !error.hidden);
    }, null, { timeout: 120_000, polling: 50 });
    const error = await page.locator('#viewer-error').textContent();
    if (error) throw new Error(error);
    const state = await page.evaluate(() => window.pointdagViewer.state());
    if (state.lastError) throw new Error(state.lastError);
    return state;
  } finally {
    await context.close();
  }
}

function median(values) {
  const v = values.filter(Number.isFinite).sort((a, b) => a - b);
  return v.length ? v[Math.floor((v.length - 1) / 2)] : NaN;
}

function row(label, states) {
  const m = (f) => median(states.map(f));
  const decode = states[0].decoder;
  const perSecond = (f) => (decode ? m((s) => (f(s) / s.decoder.ms) * 1000) : NaN);
  const fmt = (v, digits = 0) => (Number.isFinite(v) ? v.toFixed(digits) : '–');
  return `| ${label} | ${fmt(m((s) => s.firstFrameMs))} | ${fmt(m((s) => s.finestMs))} | ${states[0].levelsDrawn.join(',')} | ` +
    `${fmt(m((s) => s.tilesFetched))} | ${fmt(m((s) => s.bytesFetched / 1024), 1)} | ${fmt(m((s) => s.pointsOnScreen))} | ` +
    `${fmt(perSecond((s) => s.decoder.tiles), 1)} | ${fmt(perSecond((s) => s.decoder.voxels) / 1e6, 2)} |`;
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  const dataset = opts.dataset || (await upload(opts));
  const sse = opts.sse ? `sse=${opts.sse}` : '';
  const pages = [
    ['.pdag, JS decoder', `/datasets/${dataset}?decoder=js${sse ? `&${sse}` : ''}`],
    ['.pdag, WASM decoder', `/datasets/${dataset}?decoder=wasm${sse ? `&${sse}` : ''}`],
    ['3D Tiles (.glb, meshopt)', `/datasets/${dataset}/3dtiles${sse ? `?${sse}` : ''}`],
  ];
  const browser = await chromium.launch({ executablePath: opts.chromium, headless: true, args: CHROMIUM_ARGS });
  const lines = [
    `dataset ${dataset}, ${opts.size} px, ${opts.runs} cold runs each (medians), Chromium ${browser.version()} with SwiftShader`,
    '',
    '| page | first frame ms | finest ms | levels | tiles | KiB fetched | points drawn | decode tiles/s | decode Mvoxels/s |',
    '|---|---|---|---|---|---|---|---|---|',
  ];
  try {
    for (const [label, path] of pages) {
      const states = [];
      try {
        for (let i = 0; i < opts.runs; ++i) states.push(await measure(browser, opts, path));
        lines.push(row(label, states));
      } catch (err) {
        lines.push(`| ${label} | failed: ${err.message.split('\n')[0]} |||||||| `);
      }
    }
  } finally {
    await browser.close();
  }
  console.log(lines.join('\n'));
}

main().catch((err) => {
  console.error(`viewer_bench: ${err.message}`);
  process.exit(1);
});
