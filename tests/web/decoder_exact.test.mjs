// The browser's tile decoders against the C++ one: a real pointdagd ingests real scans, every tile
// it serves is decoded by the JavaScript decoder, by the C++ decoder compiled to WebAssembly, and by
// `pointdag decode` (binary PLY: doubles x, y, z, uchar r, g, b), and all three must give the same
// voxels in the same order, bit-exact centres (origin + (coord + 0.5) * voxelSize) and colors.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';

import { decodePdag } from '../../web/src/decoder/decode_pdag.js';
import { WASM_SKIPPED, config, loadWasm, requireFile, scan } from './lib/config.mjs';
import { Daemon, fetchTile, ingest, listTiles } from './lib/pointdagd.mjs';

const SCANS = ['tiny_1.2-with-color_1065pts.las', 'autzen_trim_pdrf3_rgb.las'];

// `pointdag decode` of the bytes: {count, centres: Float64Array(3n), colors: Uint8Array(3n) | null}.
function decodeWithCli(bytes, dir) {
  const input = join(dir, 'tile.pdag');
  const output = join(dir, 'tile.ply');
  writeFileSync(input, bytes);
  execFileSync(config.cli, ['decode', input, '-o', output], { stdio: ['ignore', 'ignore', 'pipe'] });
  const ply = readFileSync(output);
  const end = ply.indexOf('end_header\n') + 'end_header\n'.length;
  const header = ply.subarray(0, end).toString();
  const count = Number(/element vertex (\d+)/.exec(header)[1]);
  const hasColor = header.includes('property uchar red');
  const stride = hasColor ? 27 : 24;
  assert.equal(ply.length - end, count * stride, 'PLY body size');
  const view = new DataView(ply.buffer, ply.byteOffset + end);
  const centres = new Float64Array(3 * count);
  const colors = hasColor ? new Uint8Array(3 * count) : null;
  for (let i = 0; i < count; ++i) {
    for (let a = 0; a < 3; ++a) centres[3 * i + a] = view.getFloat64(stride * i + 8 * a, true);
    if (colors) for (let c = 0; c < 3; ++c) colors[3 * i + c] = view.getUint8(stride * i + 24 + c);
  }
  return { count, centres, colors };
}

function centresOf(r) {
  const out = new Float64Array(3 * r.count);
  for (let i = 0; i < out.length; ++i) out[i] = r.origin[i % 3] + (r.coords[i] + 0.5) * r.voxelSize;
  return out;
}

// Bit-exact: the doubles' bytes, so -0 and 0 or two NaNs could not pass for each other.
function assertSameVoxels(got, want, what) {
  assert.equal(got.count, want.count, `${what}: voxel count`);
  const centres = centresOf(got);
  const a = Buffer.from(centres.buffer), b = Buffer.from(want.centres.buffer);
  if (!a.equals(b)) {
    const i = centres.findIndex((v, k) => !Object.is(v, want.centres[k]));
    assert.fail(`${what}: centre ${Math.floor(i / 3)} axis ${i % 3} is ${centres[i]}, pointdag decode says ${want.centres[i]}`);
  }
  assert.deepEqual(got.colors, want.colors, `${what}: colors`);
}

describe('tiles decoded in JavaScript and WebAssembly equal pointdag decode', () => {
  let daemon, wasm, scratch;
  before(async () => {
    requireFile(config.cli, 'the pointdag CLI (build it: scripts/build)');
    SCANS.forEach(scan);
    daemon = await Daemon.start();
    wasm = await loadWasm();
    scratch = mkdtempSync(join(tmpdir(), 'pointdag-web-decode-'));
  });
  after(async () => {
    await daemon?.stop();
    if (scratch) rmSync(scratch, { recursive: true, force: true });
  });

  for (const name of SCANS) {
    test(name, async (t) => {
      const id = await ingest(daemon.url, scan(name), { name });
      const tiles = await listTiles(daemon.url, id);
      assert.ok(tiles.length > 0, 'the dataset has tiles');
      const cases = [];
      for (const tile of tiles) {
        const where = `${name} tile ${tile.level}/${tile.x}/${tile.y}/${tile.z}`;
        const bytes = await fetchTile(daemon.url, id, tile);
        const want = decodeWithCli(bytes, scratch);
        assert.equal(want.count, tile.voxels, `${where}: the hierarchy's voxel count`);
        assert.ok(want.colors, `${where}: has colors`);
        cases.push({ where, tile, bytes, want });
      }
      const voxels = cases.reduce((n, c) => n + c.want.count, 0);
      await t.test('JavaScript', () => {
        for (const { where, tile, bytes, want } of cases) {
          const js = decodePdag(bytes);
          assertSameVoxels(js, want, `${where} (JavaScript)`);
          assert.equal(js.meta.tile.level, tile.level, `${where}: metadata`);
        }
      });
      await t.test('WebAssembly', { skip: !wasm && WASM_SKIPPED }, () => {
        for (const { where, bytes, want } of cases) {
          const w = wasm.decode(bytes);
          assertSameVoxels(w, want, `${where} (WebAssembly)`);
          const js = decodePdag(bytes);
          assert.deepEqual(w.meta, js.meta, `${where}: metadata, WebAssembly vs JavaScript`);
          assert.equal(w.coords.constructor, js.coords.constructor, `${where}: coordinate array type`);
        }
      });
      t.diagnostic(`${tiles.length} tiles, ${voxels} voxels`);
    });
  }
});

// A whole-scan file in leaf mode (`pointdag encode --quality`): its VBR colors are block stream
// version 4, whose weights' contexts and endpoint predictions come from the voxels' decoded neighbours.
describe('leaf-mode files decoded in JavaScript and WebAssembly equal pointdag decode', () => {
  let wasm, scratch;
  before(async () => {
    requireFile(config.cli, 'the pointdag CLI (build it: scripts/build)');
    wasm = await loadWasm();
    scratch = mkdtempSync(join(tmpdir(), 'pointdag-web-leaf-'));
  });
  after(() => {
    if (scratch) rmSync(scratch, { recursive: true, force: true });
  });

  for (const [codec, quality] of [['vbr', '38'], ['fixed3', '34']]) {
    test(`autzen at 4 ft, ${codec} at ${quality} dB`, async (t) => {
      const file = join(scratch, `autzen-${codec}.pdag`);
      execFileSync(config.cli, ['encode', scan('autzen_trim_pdrf3_rgb.las'), '--voxel', '1.2192', '--color-codec', codec,
        '--quality', quality, '-o', file], { stdio: ['ignore', 'ignore', 'pipe'], env: { ...process.env, POINTDAG_DEVICE: 'cpu' } });
      const bytes = new Uint8Array(readFileSync(file));
      const want = decodeWithCli(bytes, scratch);
      await t.test('JavaScript', () => assertSameVoxels(decodePdag(bytes), want, `${codec} (JavaScript)`));
      await t.test('WebAssembly', { skip: !wasm && WASM_SKIPPED }, () => assertSameVoxels(wasm.decode(bytes), want, `${codec} (WebAssembly)`));
    });
  }
});
