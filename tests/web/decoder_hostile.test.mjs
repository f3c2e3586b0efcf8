// Hostile .pdag input for the browser's decoders: truncations and bit flips of a real tile, and
// headers that lie about their counts. Each must end in a PdagError (or, for a flip the format
// ignores, in the same voxels), quickly, without a crash, and the JavaScript decoder must fail
// exactly where the C++ one (compiled to WebAssembly) fails: at the same check, or with the same output.
import assert from 'node:assert/strict';
import { createHash } from 'node:crypto';
import { readFileSync } from 'node:fs';
import { before, describe, test } from 'node:test';

import { decodeBlockColors } from '../../web/src/decoder/block_colors.js';
import { decodeDag } from '../../web/src/decoder/dag_stream.js';
import { FIXED_WEIGHT_CODES_TEXT } from '../../web/src/decoder/fixed_weight_codes.js';
import { fixedWeightCodeLengths } from '../../web/src/decoder/weight_groups.js';
import { PdagError, decodePdag } from '../../web/src/decoder/decode_pdag.js';
import { WASM_SKIPPED, config, loadWasm, scan } from './lib/config.mjs';
import { denseCube, framePdag, sectionsOf, utf8, varint, writeGeometry } from './lib/pdag_writer.mjs';
import { Daemon, fetchTile, ingest, listTiles } from './lib/pointdagd.mjs';

const CODES = new Set(['Corrupt', 'ResourceLimit', 'Unsupported']);
const MAX_DECODE_MS = 2000;  // a hostile input is refused in linear time: far below this

// 'ok' with the result, or the PdagError's code; anything else thrown fails the test.
function outcome(decode, bytes, what) {
  const start = performance.now();
  let result;
  try {
    result = { code: 'ok', value: decode(bytes) };
  } catch (err) {
    if (!(err instanceof PdagError)) throw new Error(`${what}: threw ${err?.stack ?? err}, not a PdagError`);
    assert.ok(CODES.has(err.code), `${what}: unknown code ${err.code}`);
    result = { code: err.code, message: err.message, detail: err.detail };
  }
  const ms = performance.now() - start;
  assert.ok(ms < MAX_DECODE_MS, `${what}: took ${ms.toFixed(0)} ms`);
  return result;
}

// The check that refused the input, as its message says: the C++ one names kTruncated, and gives no
// detail of a JSON syntax error where the JavaScript parser names the offset.
const failurePoint = (detail) => detail.replace(/^(Truncated|Malformed): /, '').replace(/(not valid JSON).*/, '$1');

function sameVoxels(a, b) {
  return a.count === b.count && Buffer.from(a.coords.buffer).equals(Buffer.from(b.coords.buffer)) &&
         (a.colors === null ? b.colors === null : b.colors !== null && Buffer.from(a.colors).equals(Buffer.from(b.colors)));
}

// A deterministic PRNG (xorshift32), so a failure names a case that reproduces.
function prng(seed) {
  let s = seed;
  return (n) => {
    s ^= s << 13;
    s ^= s >>> 17;
    s ^= s << 5;
    return (s >>> 0) % n;
  };
}

// Every cut of a DAG stream, and 400 single-bit flips of it, end in a PdagError or a valid DAG; the
// cuts `refused(length)` names must not decode.
function cutsAndFlipsFailCleanly(stream, flipSeed, refused) {
  const decode = (b) => decodeDag(b, 2 ** 32);
  for (let length = 0; length < stream.length; ++length) {
    const cut = outcome(decode, stream.subarray(0, length), `cut at ${length}`);
    if (refused(length)) assert.notEqual(cut.code, 'ok', `cut at ${length}`);
  }
  const next = prng(flipSeed);
  for (let trial = 0; trial < 400; ++trial) {
    const flipped = stream.slice();
    const at = next(flipped.length);
    flipped[at] ^= 1 << next(8);
    outcome(decode, flipped, `bit flip ${trial} at ${at}`);
  }
}

describe('hostile tiles', () => {
  let tile, wasm, reference;
  // Both decoders on the bytes; they must agree. Returns the JavaScript outcome.
  const both = (bytes, what) => {
    const js = outcome((b) => decodePdag(b), bytes, `${what} (JavaScript)`);
    if (wasm) {
      if (wasm.broken) assert.fail(`${what}: the WebAssembly decoder aborted earlier`);
      const w = outcome((b) => wasm.decode(b), bytes, `${what} (WebAssembly)`);
      assert.equal(js.code, w.code, `${what}: JavaScript says ${js.message ?? 'ok'}, WebAssembly ${w.message ?? 'ok'}`);
      if (js.code === 'ok') assert.ok(sameVoxels(js.value, w.value), `${what}: the decoders give different voxels`);
      else assert.equal(failurePoint(js.detail), failurePoint(w.detail), `${what}: the decoders fail at different checks`);
    }
    return js;
  };

  before(async () => {
    const daemon = await Daemon.start();
    try {
      const id = await ingest(daemon.url, scan('autzen_trim_pdrf3_rgb.las'), { name: 'autzen' });
      // The tile of median size: real geometry and VBR colors, small enough to truncate at every length.
      const tiles = (await listTiles(daemon.url, id)).sort((a, b) => a.voxels - b.voxels);
      tile = await fetchTile(daemon.url, id, tiles[Math.floor(tiles.length / 2)]);
    } finally {
      await daemon.stop();
    }
    wasm = await loadWasm();
    reference = decodePdag(tile);
  });

  // Without the WebAssembly build, every case below runs the JavaScript decoder alone.
  test('the WebAssembly decoder takes part', (t) => { if (!wasm) t.skip(WASM_SKIPPED); });

  test('the tile decodes', () => {
    assert.ok(reference.count > 0 && reference.colors);
    assert.equal(both(tile, 'the tile').code, 'ok');
  });

  test('every truncation of the file is Corrupt', () => {
    for (let n = 0; n < tile.length; ++n) assert.equal(both(tile.subarray(0, n), `first ${n} bytes`).code, 'Corrupt');
  });

  test('every single-bit flip of the file is caught (CRC32C)', () => {
    const next = prng(12345);
    for (let at = 0; at < tile.length; ++at) {
      const bytes = tile.slice();
      bytes[at] ^= 1 << next(8);
      const r = both(bytes, `flip at byte ${at}`);
      assert.ok(r.code !== 'ok', `flip at byte ${at} decoded`);
    }
  });

  // Past the CRCs: the section is damaged and the container re-framed with valid CRCs, so the
  // damage reaches the metadata, geometry and color decoders themselves.
  for (const tag of ['meta', 'geometry', 'colors']) {
    test(`truncated and bit-flipped ${tag} sections with valid CRCs`, (t) => {
      const sections = sectionsOf(tile);
      const index = sections.findIndex(([name]) => name === tag);
      const data = sections[index][1];
      const reframe = (payload) => framePdag(sections.map(([name, d], i) => [name, i === index ? payload : d]));
      const counts = { ok: 0 };
      for (let n = 0; n < data.length; n += Math.max(1, Math.floor(data.length / 1500))) {
        const r = both(reframe(data.subarray(0, n)), `${tag} cut to ${n} bytes`);
        counts[r.code] = (counts[r.code] ?? 0) + 1;
        if (r.code !== 'ok') continue;
        if (tag === 'colors' && n === 0) {
          assert.equal(r.value.colors, null, 'an empty colors section is no colors');
        } else {
          // The geometry's range coder ends with 5 flush bytes, of which the decoder may not need the
          // last few (it reads zeros past the end and fails only after more than 4 of them).
          assert.ok(tag === 'geometry' && n >= data.length - 4, `${tag} cut to ${n} of ${data.length} bytes decoded`);
          assert.ok(sameVoxels(r.value, reference), `${tag} cut to ${n} bytes decoded to other voxels`);
        }
      }
      const next = prng(777);
      for (let k = 0; k < 3000; ++k) {
        const payload = data.slice();
        const flips = 1 + next(3);
        for (let f = 0; f < flips; ++f) payload[next(payload.length)] ^= 1 << next(8);
        const r = both(reframe(payload), `${tag} flip case ${k}`);
        counts[r.code] = (counts[r.code] ?? 0) + 1;
      }
      t.diagnostic(`${tag}: ${JSON.stringify(counts)}`);
    });
  }

  const meta = (fields) => utf8(JSON.stringify({ depth: 8, voxel_size: 0.5, origin: [0, 0, 0], ...fields }));
  // One of the lying files: refused with `code` quickly, and by JavaScript without allocating by the lie.
  const refused = (bytes, code, what) => {
    const before = process.memoryUsage().arrayBuffers;
    assert.equal(both(bytes, what).code, code, what);
    const grown = process.memoryUsage().arrayBuffers - before;
    assert.ok(grown < 16 << 20, `${what}: ${grown} bytes of array buffers allocated`);
  };

  test('headers that lie about counts are refused before allocating', () => {
    const cube8 = writeGeometry(denseCube(8, 1));
    refused(framePdag([['meta', meta({ voxels: 2 ** 27 + 1 })], ['geometry', cube8]]), 'ResourceLimit', 'metadata above the voxel limit');
    refused(framePdag([['meta', meta({ voxels: 2 ** 53 })], ['geometry', cube8]]), 'ResourceLimit', 'metadata declaring 2^53 voxels');
    // A level table of a full octree (299,593 nodes) over a few bytes of payload.
    const fullTable = [1, 8, 64, 512, 4096, 32768, 262144];
    const lying = new Uint8Array([1, 1, 8, 1, ...fullTable.flatMap(varint), 0, 0, 0, 0, 0]);
    refused(framePdag([['meta', meta({ voxels: 2 ** 27 })], ['geometry', lying]]), 'Corrupt', 'more nodes than the payload can hold');
    refused(framePdag([['meta', meta({ voxels: 100 })], ['geometry', lying]]), 'Corrupt', 'more nodes than the voxels allow');
    const huge = new Uint8Array([1, 1, 8, 1, ...varint(1), ...varint(2 ** 40), 0]);
    refused(framePdag([['meta', meta({ voxels: 2 ** 27 })], ['geometry', huge]]), 'Corrupt', 'a level of 2^40 nodes');
    // Real DAGs of a few bytes whose counts pass every table check: the root's count is the lie.
    refused(framePdag([['meta', meta({ voxels: 2 ** 27, depth: 9 })], ['geometry', writeGeometry(denseCube(9, 1))]]),
            'ResourceLimit', 'a depth-9 solid cube (1.5e8 nodes) in mipmap mode');
    refused(framePdag([['meta', meta({ voxels: 2 ** 27, depth: 21 })], ['geometry', writeGeometry(denseCube(21, 0))]]),
            'ResourceLimit', 'a depth-21 solid cube (2^63 voxels)');
    refused(framePdag([['meta', meta({ voxels: 2 ** 24 })], ['geometry', writeGeometry(denseCube(8, 0))], ['colors', new Uint8Array([0, 1, 2, 3])]]),
            'Corrupt', 'raw colors for 2^24 voxels in 3 bytes');
    // Block colors declaring the cube's 19 million node colors over 2 payload bytes.
    const blockStream = (payload) => new Uint8Array([3, 1, 2, 0, 0, ...varint(19173961), ...varint(19173961), ...varint(payload.length), ...payload]);
    refused(framePdag([['meta', meta({ voxels: 2 ** 24 })], ['geometry', cube8], ['colors', blockStream([0, 0])]]),
            'Corrupt', 'block colors for 19 million nodes in 2 bytes');
    refused(framePdag([['meta', meta({ voxels: 2 ** 24 })], ['geometry', cube8], ['colors', blockStream(new Uint8Array(1500).fill(0x5a))]]),
            'Corrupt', 'block colors for 19 million nodes in 1500 bytes');
  });

  test('voxel colors only (codec bit 7): read in mipmap mode, refused in leaf mode', () => {
    // The solid cube of side 4: 64 voxels; in mipmap mode 73 nodes (the brick, its 8 cells, the voxels).
    const raw = (codecByte) => new Uint8Array([codecByte, ...Array.from({ length: 3 * 64 }, (_, i) => (7 * i) & 0xff)]);
    const cube = (mode, colors) => framePdag([['meta', meta({ voxels: 64, depth: 2 })], ['geometry', writeGeometry(denseCube(2, mode))],
                                              ['colors', colors]]);
    const decoded = both(cube(1, raw(0x80)), 'voxel colors of a mipmap cube');
    assert.equal(decoded.code, 'ok', decoded.message);
    assert.deepEqual(decoded.value.colors, raw(0x80).subarray(1));
    refused(cube(0, raw(0x80)), 'Corrupt', 'voxel colors only in leaf mode');
    refused(cube(1, raw(0)), 'Corrupt', 'the voxels\' colors where every node\'s are declared');
    assert.equal(both(cube(0, raw(0)), 'voxel colors of a leaf cube').code, 'ok');
  });

  test('formats these decoders do not read are Unsupported, not Corrupt', () => {
    const sections = sectionsOf(tile);
    const withSection = (tag, change) => framePdag(sections.map(([name, d]) => [name, name === tag ? change(d.slice()) : d]));
    assert.equal(both(framePdag(sections, { major: 2 }), 'major version 2').code, 'Unsupported');
    assert.equal(both(withSection('geometry', (g) => { g[1] = 0; return g; }), 'zstd geometry').code, 'Unsupported');
    // Version 8's second byte is its depth and mode: 0 there is a bad depth, not zstd.
    assert.equal(both(withSection('geometry', (g) => { g[0] = 8; g[1] = 0; return g; }), 'version 8 of depth 0').code, 'Corrupt');
    for (const codec of [1, 4, 5, 6, 7, 8]) {
      assert.equal(both(withSection('colors', (c) => { c[0] = codec; return c; }), `colors codec ${codec}`).code, 'Unsupported');
    }
    assert.equal(both(withSection('colors', (c) => { c[0] = 9; return c; }), 'colors codec 9').code, 'Corrupt');
  });

  test('container rules: sections twice, missing, or empty', () => {
    const [m, g, c] = sectionsOf(tile);
    assert.equal(both(framePdag([m, g, c, m]), 'meta twice').code, 'Corrupt');
    assert.equal(both(framePdag([m, c]), 'no geometry').code, 'Corrupt');
    assert.equal(both(framePdag([g, c]), 'no meta').code, 'Corrupt');
    // An unknown section is skipped; an empty colors section is no colors.
    const extra = both(framePdag([m, ['future', utf8('x')], g, c]), 'an unknown section');
    assert.ok(extra.code === 'ok' && sameVoxels(extra.value, reference));
    const colorless = both(framePdag([m, g, ['colors', new Uint8Array(0)]]), 'an empty colors section');
    assert.equal(colorless.code, 'ok');
    assert.equal(colorless.value.colors, null);
    assert.deepEqual(colorless.value.coords, reference.coords);
    for (const [what, fields] of [['voxels 1.0', '"voxels": 1.0'], ['voxels -0', '"voxels": -0'], ['depth "8"', '"depth": "8"']]) {
      const text = new TextDecoder().decode(m[1]).replace(/"voxels": ?\d+|"depth": ?\d+/, fields);
      assert.equal(both(framePdag([['meta', utf8(text)], g, c]), `metadata ${what}`).code, 'Corrupt');
    }
    const source = JSON.parse(new TextDecoder().decode(m[1]));
    source.source = 5;
    assert.equal(both(framePdag([['meta', utf8(JSON.stringify(source))], g, c]), 'metadata source 5').code, 'Corrupt');
  });
});

// Geometry stream versions 1 (coder 2 without edge neighbours), 2 (without the mixer), 3 (without
// the mixer's sides model), 4 (before version 5's pattern models and height-3 and -4 slots) and 5
// (before version 8's young flags, weights and compact framing) still decode: the fuzz seeds of tiny
// at 40 ft in all six versions hold one DAG (tests/codec/dag_stream_test.cc checks the same in C++).
describe('geometry stream versions', () => {
  const seed = (name) => new Uint8Array(readFileSync(new URL(`../../fuzz/seeds/dag_stream/${name}`, import.meta.url)));
  test('coder 2 versions 1 to 5 and 8 decode to the same DAG', () => {
    for (const mode of ['leaves', 'mipmap']) {
      const v1 = seed(`${mode}_spatial.bin`);
      assert.equal(v1[0], 1);
      for (const version of [2, 3, 4, 5, 8]) {
        const stream = seed(`${mode}_spatial_v${version}.bin`);
        assert.equal(stream[0], version);
        assert.deepEqual(decodeDag(stream), decodeDag(v1), `${mode}, version ${version}`);
      }
    }
  });
  // Coder 3 in version 6 and in version 7 (prefix-coded references, the tiles' stream since fixship):
  // the seeds hold version 5's DAG; every cut is refused (the prefix-coded masks end the stream,
  // without flush bytes); flips end in a PdagError or a valid DAG (C++: DagStream.TableCoderRoundTrips,
  // DagStream.PrefixCodedReferencesRoundTrip).
  for (const [suffix, version] of [['table', 6], ['table_v7', 7]]) {
    test(`coder 3 version ${version} decodes to the same DAG, and cut or flipped fails cleanly`, () => {
      for (const mode of ['leaves', 'mipmap']) {
        const stream = seed(`${mode}_${suffix}.bin`);
        assert.equal(stream[0], version);
        assert.equal(stream[1], 3);
        assert.deepEqual(decodeDag(stream), decodeDag(seed(`${mode}_spatial_v5.bin`)), mode);
      }
      cutsAndFlipsFailCleanly(seed(`leaves_${suffix}.bin`), version, () => true);
    });
  }
  // Version 5 merges the slots it decodes: a cut or flipped stream must still end in a PdagError or
  // in some valid DAG, never in an exception of another kind.
  test('version 5 cut or flipped fails cleanly', () => {
    const stream = seed('leaves_spatial_v5.bin');
    // The range decoder reads up to 4 missing bytes as zeros (every version: the container's CRC
    // catches such a cut), so only a cut of 5 bytes or more must be refused.
    cutsAndFlipsFailCleanly(stream, 5, (length) => length + 5 <= stream.length);
  });
  // Version 8 has no level table and drops the zero bytes its decoder infers: a cut decodes on zeros
  // and must end in a PdagError or some valid DAG; its header's reserved bits and depth are checked.
  test('version 8 cut, flipped or with a lying header fails cleanly', () => {
    const stream = seed('leaves_spatial_v8.bin');
    cutsAndFlipsFailCleanly(stream, 8, (length) => length < 2);
    for (const header of [9 | 1 << 6, 22, 1]) {
      const bad = stream.slice();
      bad[1] = header;
      assert.throws(() => decodeDag(bad, 2 ** 32), PdagError);
    }
    assert.throws(() => decodeDag(stream, 100), PdagError);  // the caller's bound on nodes
  });
});

// Block color stream versions 1 (channel differences) and 2 still decode: the version 2 seeds hold
// the version 1 seeds' decoded colors, re-encoded exactly, the version 3 and 4 seeds those of
// version 2 for the voxels 0..count-1 in Morton order (tests/codec/color_test.cc and
// block_stream_spatial_test.cc check C++ alike); versions 3 and 4 need the voxels.
describe('color stream versions', () => {
  test('vbr and fixed3 versions 1 to 4 decode to the same colors', () => {
    const seed = (name) => new Uint8Array(readFileSync(new URL(`../../fuzz/seeds/${name}`, import.meta.url)));
    for (const name of ['color_vbr/vbrquality34coderzstd', 'color_fixed3/fixed3quality34']) {
      const v1 = seed(`${name}.bin`);
      const v2 = seed(`${name}_v2.bin`);
      const v3 = seed(`${name}_v3.bin`);
      const v4 = seed(`${name}_v4.bin`);
      const count = v1[0] | (v1[1] << 8) | (v1[2] << 16);
      assert.equal(v1[3], 1);
      assert.equal(v2[3], 2);
      assert.equal(v3[3], 3);
      assert.equal(v4[3], 4);
      const colors = decodeBlockColors(v1.subarray(3), count);
      assert.deepEqual(decodeBlockColors(v2.subarray(3), count), colors);
      const coords = new Uint16Array(3 * count);  // cell of Morton code i: x, y, z from bits 3k+2, 3k+1, 3k
      for (let i = 0; i < count; ++i) {
        for (let bit = 0; 3 * bit < 16; ++bit) {
          coords[3 * i] |= ((i >> (3 * bit + 2)) & 1) << bit;
          coords[3 * i + 1] |= ((i >> (3 * bit + 1)) & 1) << bit;
          coords[3 * i + 2] |= ((i >> (3 * bit)) & 1) << bit;
        }
      }
      for (const spatial of [v3, v4]) {
        assert.deepEqual(decodeBlockColors(spatial.subarray(3), count, coords), colors);
        assert.throws(() => decodeBlockColors(spatial.subarray(3), count), PdagError);
      }
    }
  });
  // Version 6 (tiles: weights in groups, fixed codes): the version 2 seeds' colors; version 5 (never
  // released) is refused; every cut and 400 flips end in a PdagError or colors.
  test('vbr and fixed3 version 6 decode to the same colors, and cut or flipped fail cleanly', () => {
    const seed = (name) => new Uint8Array(readFileSync(new URL(`../../fuzz/seeds/${name}`, import.meta.url)));
    for (const name of ['color_vbr/vbrquality34coderzstd', 'color_fixed3/fixed3quality34']) {
      const v2 = seed(`${name}_v2.bin`);
      const v6 = seed(`${name}_v6.bin`);
      const count = v2[0] | (v2[1] << 8) | (v2[2] << 16);
      assert.equal(v6[3], 6);
      const stream = v6.subarray(3);
      assert.deepEqual(decodeBlockColors(stream, count), decodeBlockColors(v2.subarray(3), count));
      const five = stream.slice();
      five[0] = 5;
      assert.throws(() => decodeBlockColors(five, count), PdagError);
      for (let length = 0; length < stream.length; ++length) {
        assert.notEqual(outcome((b) => decodeBlockColors(b, count), stream.subarray(0, length), `cut at ${length}`).code, 'ok');
      }
      const next = prng(6);
      for (let trial = 0; trial < 400; ++trial) {
        const flipped = stream.slice();
        flipped[next(flipped.length)] ^= 1 << next(8);
        outcome((b) => decodeBlockColors(b, count), flipped, `flip ${trial}`);
      }
    }
  });
});

// The JavaScript copy of version 6's fixed codes is the normative table byte for byte, and the table
// is the one whose SHA-256 the spec gives (C++: FixedWeightCodes.AreTheNormativeTable).
describe('block color stream version 6 codes', () => {
  test('are proto/tables/block_weight_codes_v6.txt', () => {
    const table = readFileSync(new URL('../../proto/tables/block_weight_codes_v6.txt', import.meta.url), 'utf8');
    assert.equal(FIXED_WEIGHT_CODES_TEXT, table, 'regenerate: weight_codes_trainer emit (tools/weight_codes_trainer.cc)');
    const spec = readFileSync(new URL('../../proto/PDAG_FORMAT.md', import.meta.url), 'utf8');
    const sha = createHash('sha256').update(table).digest('hex');
    assert.ok(spec.includes(`SHA-256 \`${sha}\``), `the spec's SHA-256 of the table is not ${sha}`);
    const codes = fixedWeightCodeLengths(table);
    let lengths = 0;
    for (let bits = 1; bits <= 4; ++bits) for (const code of codes[bits]) lengths += code.filter((l) => l > 0).length;
    assert.equal(lengths, 6976);
  });
});
