// Tiles decoded per second under Node: the JavaScript decoder vs the C++ decoder compiled to
// WebAssembly, on every tile of a dataset served by pointdagd, plus `pointdag decode` for reference.
//
//   node web/bench/decode_bench.mjs --daemon http://127.0.0.1:8080 --dataset ID [--reps 20]
//   node web/bench/decode_bench.mjs --scan ../shared/data/lion_takanawa_pdrf7_rgb.las [--pointdagd build/server/pointdagd]
//   options: --wasm build/web-wasm/pdag_decoder.mjs  --native build/tests/web/decode_native_bench ("" to skip)
//
// Each pass decodes every tile once; passes alternate between the backends (so that a busy machine
// slows both alike) after one warm-up pass each. Reported: the median pass. The native row is the
// same C++ DecodePdag built natively (-O2), run in its own process over the same tiles.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { basename, join } from 'node:path';
import { parseArgs } from 'node:util';

import { config, loadWasm } from '../../tests/web/lib/config.mjs';
import { Daemon, fetchTile, ingest, listTiles } from '../../tests/web/lib/pointdagd.mjs';
import { decodePdag } from '../src/decoder/decode_pdag.js';

const { values: args } = parseArgs({
  options: {
    daemon: { type: 'string' }, dataset: { type: 'string' }, scan: { type: 'string' },
    pointdagd: { type: 'string', default: config.pointdagd }, wasm: { type: 'string', default: config.wasmDecoder },
    native: { type: 'string', default: join(config.root, 'build/tests/web/decode_native_bench') }, reps: { type: 'string', default: '20' },
  },
});

async function tilesOf() {
  if (args.daemon && args.dataset) {
    const tiles = await listTiles(args.daemon, args.dataset);
    return { name: args.dataset, bytes: await Promise.all(tiles.map((t) => fetchTile(args.daemon, args.dataset, t))) };
  }
  if (!args.scan) throw new Error('give --daemon URL --dataset ID, or --scan FILE');
  const daemon = await Daemon.start({ binary: args.pointdagd });
  try {
    const id = await ingest(daemon.url, args.scan, { name: basename(args.scan) });
    const tiles = await listTiles(daemon.url, id);
    return { name: basename(args.scan), bytes: await Promise.all(tiles.map((t) => fetchTile(daemon.url, id, t))) };
  } finally {
    await daemon.stop();
  }
}

const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];

const { name, bytes } = await tilesOf();
const reps = Number(args.reps);
config.wasmDecoder = args.wasm;
const wasm = await loadWasm();
const backends = [['JavaScript', (b) => decodePdag(b)]];
if (wasm) backends.push(['WebAssembly', (b) => wasm.decode(b)]);
const voxels = bytes.reduce((n, b) => n + decodePdag(b).count, 0);
const megabytes = bytes.reduce((n, b) => n + b.length, 0) / 1e6;

const passes = new Map(backends.map(([label]) => [label, []]));
for (let rep = -1; rep < reps; ++rep) {
  for (const [label, decode] of backends) {
    const start = performance.now();
    for (const b of bytes) decode(b);
    if (rep >= 0) passes.get(label).push(performance.now() - start);
  }
}

const rows = backends.map(([label]) => [label, median(passes.get(label))]);
if (args.native) {
  const dir = mkdtempSync(join(tmpdir(), 'pointdag-bench-'));
  try {
    const files = bytes.map((b, i) => {
      writeFileSync(join(dir, `${i}.pdag`), b);
      return join(dir, `${i}.pdag`);
    });
    rows.push(['C++ native (DecodePdag)', Number(execFileSync(args.native, [String(reps), ...files], { encoding: 'utf8' }))]);
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
}

console.log(`${name}: ${bytes.length} tiles, ${voxels} voxels, ${megabytes.toFixed(3)} MB; median of ${reps} passes (node ${process.version})`);
console.log('| decoder | tiles | voxels | MB | ms | tiles/s | Mvoxels/s |');
console.log('|---|---:|---:|---:|---:|---:|---:|');
for (const [label, ms] of rows) {
  console.log(`| ${label} | ${bytes.length} | ${voxels} | ${megabytes.toFixed(3)} | ${ms.toFixed(1)} | ${(bytes.length / ms * 1000).toFixed(0)} | ${(voxels / ms / 1000).toFixed(2)} |`);
}
