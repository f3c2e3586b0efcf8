// Tiles decoded per second in a browser's worker (headless Chromium, playwright-core): the
// decode worker (web/src/decoder/decode_worker.js, bundled by esbuild) on every tile of a dataset,
// backend 'js' vs 'wasm', from the worker's own decodeMs. Passes alternate between the backends
// after two warm-up passes each; reported: the median pass.
//
//   node web/bench/worker_bench.mjs --scan ../shared/data/lion_takanawa_pdrf7_rgb.las [--reps 20]
//   node web/bench/worker_bench.mjs --daemon URL --dataset ID
import { build } from 'esbuild';
import { copyFileSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import http from 'node:http';
import { tmpdir } from 'node:os';
import { basename, dirname, extname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';
import { chromium } from 'playwright-core';

import { config, requireFile } from '../../tests/web/lib/config.mjs';
import { Daemon, fetchTile, ingest, listTiles } from '../../tests/web/lib/pointdagd.mjs';
import { decodePdag } from '../src/decoder/decode_pdag.js';

const { values: args } = parseArgs({
  options: {
    daemon: { type: 'string' }, dataset: { type: 'string' }, scan: { type: 'string' },
    pointdagd: { type: 'string', default: config.pointdagd }, wasm: { type: 'string', default: config.wasmDecoder },
    chromium: { type: 'string', default: '/usr/bin/chromium' }, reps: { type: 'string', default: '20' },
  },
});

async function tiles() {
  if (args.daemon && args.dataset) {
    return Promise.all((await listTiles(args.daemon, args.dataset)).map((t) => fetchTile(args.daemon, args.dataset, t)));
  }
  if (!args.scan) throw new Error('give --daemon URL --dataset ID, or --scan FILE');
  const daemon = await Daemon.start({ binary: args.pointdagd });
  try {
    const id = await ingest(daemon.url, args.scan, { name: basename(args.scan) });
    return await Promise.all((await listTiles(daemon.url, id)).map((t) => fetchTile(daemon.url, id, t)));
  } finally {
    await daemon.stop();
  }
}

// The page: posts every tile to the worker, pass after pass, and keeps the sum of decodeMs.
const PAGE = `<!doctype html><script type="module">
const count = await (await fetch('count')).json();
const tiles = await Promise.all([...Array(count).keys()].map(async (i) => new Uint8Array(await (await fetch('tile' + i)).arrayBuffer())));
const glue = new URL('pdag_decoder.mjs', location.href).href;
const worker = new Worker('worker.js?wasm=' + encodeURIComponent(glue), { type: 'module' });
const pending = new Map();
worker.onmessage = ({ data }) => { pending.get(data.id)(data); pending.delete(data.id); };
let id = 0;
const decode = (bytes, backend) => new Promise((resolve) => {
  pending.set(++id, resolve);
  const buffer = bytes.slice().buffer;
  worker.postMessage({ id, bytes: buffer, backend }, [buffer]);
});
const passes = { js: [], wasm: [] };
for (let rep = -2; rep < REPS; ++rep) {
  for (const backend of ['js', 'wasm']) {
    let ms = 0;
    for (const t of tiles) {
      const r = await decode(t, backend);
      if (!r.ok) throw new Error(r.error);
      ms += r.decodeMs;
    }
    if (rep >= 0) passes[backend].push(ms);
  }
}
window.result = { passes, ua: navigator.userAgent };
</script>`;

const bytes = await tiles();
const dir = mkdtempSync(join(tmpdir(), 'pointdag-worker-bench-'));
let server, browser;
try {
  await build({ entryPoints: [join(dirname(fileURLToPath(import.meta.url)), '../src/decoder/decode_worker.js')],
                bundle: true, format: 'esm', minify: true, outfile: join(dir, 'worker.js'), logLevel: 'warning' });
  copyFileSync(requireFile(args.wasm, 'the WebAssembly decoder (build it: scripts/build)'), join(dir, 'pdag_decoder.mjs'));
  bytes.forEach((b, i) => writeFileSync(join(dir, `tile${i}`), b));
  writeFileSync(join(dir, 'count'), String(bytes.length));
  writeFileSync(join(dir, 'index.html'), PAGE.replace('REPS', String(Number(args.reps))));
  const types = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript' };
  server = http.createServer((req, res) => {
    const path = join(dir, basename(new URL(req.url, 'http://x').pathname) || 'index.html');
    try {
      const body = readFileSync(path);
      res.writeHead(200, { 'Content-Type': types[extname(path)] ?? 'application/octet-stream' });
      res.end(body);
    } catch {
      res.writeHead(404).end();
    }
  }).listen(0, '127.0.0.1');
  await new Promise((resolve) => server.on('listening', resolve));
  browser = await chromium.launch({ executablePath: args.chromium, args: ['--no-sandbox', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--no-first-run'] });
  const page = await browser.newPage();
  let failure = null;
  page.on('pageerror', (err) => { failure = err; });
  await page.goto(`http://127.0.0.1:${server.address().port}/index.html`);
  await page.waitForFunction(() => window.result, null, { timeout: 600000, polling: 200 }).catch((err) => { throw failure ?? err; });
  const { passes, ua } = await page.evaluate(() => window.result);
  const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];
  const megabytes = bytes.reduce((n, b) => n + b.length, 0) / 1e6;
  const voxels = bytes.reduce((n, b) => n + decodePdag(b).count, 0);
  console.log(`${args.scan ? basename(args.scan) : args.dataset}: ${bytes.length} tiles, ${voxels} voxels, ${megabytes.toFixed(3)} MB; decodeMs summed over the tiles, median of ${args.reps} passes; ${ua.match(/Chrome\/[\d.]+/)?.[0]}`);
  console.log('| worker backend | ms | tiles/s | Mvoxels/s |');
  console.log('|---|---:|---:|---:|');
  for (const backend of ['js', 'wasm']) {
    const ms = median(passes[backend]);
    console.log(`| ${backend} | ${ms.toFixed(1)} | ${(bytes.length / ms * 1000).toFixed(0)} | ${(voxels / ms / 1000).toFixed(2)} |`);
  }
} finally {
  await browser?.close();
  server?.close();
  rmSync(dir, { recursive: true, force: true });
}
