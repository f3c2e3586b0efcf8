// The browser's decoder of per-tile shadow layers (web/src/decoder/shadow_layer.js) on vectors
// written from proto/SHADOW_FORMAT.md §2: a layer written out byte by byte, round trips of
// patterns, and every malformed case the spec lists, each refused with a PdagError, never another
// exception. The layers pointdagd writes (the C++ encoder) are checked in shadow_layer_daemon.test.mjs.
import assert from 'node:assert/strict';
import { describe, test } from 'node:test';

import { crc32c } from '../../web/src/decoder/crc32c.js';
import { PdagError } from '../../web/src/decoder/pdag_error.js';
import { SHADOW_KIND_SUN_HOURS, decodeShadowLayer } from '../../web/src/decoder/shadow_layer.js';
import { encodeShadowLayer, frameShadowLayer, shadowRuns, shadowTokens } from './lib/shadow_layer_writer.mjs';

// The PdagError a decode throws (its code and detail); fails when it decodes or throws anything else.
function refusal(bytes, tileVoxels) {
  try {
    decodeShadowLayer(bytes, tileVoxels);
  } catch (err) {
    if (!(err instanceof PdagError)) throw new Error(`threw ${err?.stack ?? err}, not a PdagError`);
    return err;
  }
  assert.fail('the layer decoded');
}

describe('valid layers', () => {
  test('a layer written byte by byte from the spec decodes to its voxels', () => {
    // 5 voxels: shadowed, shadowed, shadowed, lit, lit; sun hours of 24 samples.
    const runs = [0x00, 0x02, 0xff, 0x01];
    const bytes = Uint8Array.from([
      0x50, 0x44, 0x53, 0x48, 1, 1, 24, 0, 5, 0, 0, 0,
      ...new Uint8Array(Uint32Array.of(crc32c(Uint8Array.from(runs))).buffer), ...runs]);
    assert.equal(crc32c(new TextEncoder().encode('123456789')), 0xe3069283); // the CRC-32C check value
    const layer = decodeShadowLayer(bytes, 5);
    assert.equal(layer.kind, SHADOW_KIND_SUN_HOURS);
    assert.equal(layer.samples, 24);
    assert.equal(layer.count, 5);
    assert.deepEqual([...layer.light], [0, 0, 0, 255, 255]);
    // An ArrayBuffer (what fetch gives) decodes the same.
    assert.deepEqual(decodeShadowLayer(bytes.slice().buffer, 5).light, layer.light);
  });

  test('version 2, byte by byte: a run token, then a literal token', () => {
    // 6 voxels: 0 0 0 (token 4 = a run of 3, value 0), then 255 7 9 (token 5 = 3 literals).
    const body = [4, 0, 5, 255, 7, 9];
    const bytes = Uint8Array.from([
      0x50, 0x44, 0x53, 0x48, 2, 1, 6, 0, 6, 0, 0, 0,
      ...new Uint8Array(Uint32Array.of(crc32c(Uint8Array.from(body))).buffer), ...body]);
    assert.deepEqual([...decodeShadowLayer(bytes, 6).light], [0, 0, 0, 255, 7, 9]);
    assert.deepEqual(shadowTokens(Uint8Array.of(0, 0, 0, 255, 7, 9)), Uint8Array.from(body));
  });

  const patterns = {
    'one voxel': [128],
    'all lit': new Array(1000).fill(255),
    'all shadowed (a run of 70000: a 3-byte varint)': new Array(70000).fill(0),
    alternating: Array.from({ length: 301 }, (_, i) => (i & 1 ? 255 : 0)),
    'sun-hour steps': Array.from({ length: 4096 }, (_, i) => Math.floor(i / 129) * 8),
    'no two neighbours alike (literals of more than 64: a 2-byte token)': Array.from({ length: 1000 }, (_, i) => (i * 37) % 251),
  };
  for (const [name, values] of Object.entries(patterns)) {
    for (const version of [1, 2]) {
      test(`round trip, version ${version}: ${name}`, () => {
        const light = Uint8Array.from(values);
        const layer = decodeShadowLayer(encodeShadowLayer(light, { kind: 1, samples: 1440, version }), light.length);
        assert.equal(layer.samples, 1440);
        assert.deepEqual(layer.light, light);
      });
    }
  }
});

describe('malformed layers are refused', () => {
  const light = Uint8Array.from([0, 0, 0, 255, 255, 7]);
  const runs = shadowRuns(light);
  const n = light.length;
  const cases = {
    'shorter than the header': [encodeShadowLayer(light).subarray(0, 15), n, 'Corrupt', /header/],
    'a wrong magic': [frameShadowLayer(runs, { magic: 'PDAG', count: n }), n, 'Corrupt', /magic/],
    'another version': [frameShadowLayer(runs, { version: 3, count: n }), n, 'Unsupported', /version 3/],
    'an unknown kind': [frameShadowLayer(runs, { kind: 2, count: n }), n, 'Corrupt', /kind 2/],
    'no samples': [frameShadowLayer(runs, { samples: 0, count: n }), n, 'Corrupt', /0 samples/],
    '1441 samples': [frameShadowLayer(runs, { kind: 1, samples: 1441, count: n }), n, 'Corrupt', /1441 samples/],
    'one light (kind 0) with 2 samples': [frameShadowLayer(runs, { samples: 2, count: n }), n, 'Corrupt', /one light with 2 samples/],
    'no voxels': [frameShadowLayer(new Uint8Array(0), { count: 0 }), 0, 'Corrupt', /no voxels/],
    'a CRC mismatch': [frameShadowLayer(runs, { count: n, crc: crc32c(runs) ^ 1 }), n, 'Corrupt', /CRC/],
    'a count other than the tile\'s': [frameShadowLayer(runs, { count: n + 1 }), n, 'Corrupt', /7 voxels for a tile of 6/],
    'a run passing n': [frameShadowLayer(Uint8Array.from([0, 2, 255, 3]), { count: n }), n, 'Corrupt', /passes/],
    'a run of 2^32 (longer than any count)': [frameShadowLayer(Uint8Array.from([0, 0xff, 0xff, 0xff, 0xff, 0x0f]), { count: n }), n, 'Corrupt', /passes/],
    'runs ending before n': [frameShadowLayer(Uint8Array.from([0, 2, 255, 1]), { count: n }), n, 'Corrupt', /end after 5 of 6/],
    'a run without its length': [frameShadowLayer(Uint8Array.from([0, 2, 255]), { count: n }), n, 'Corrupt', /no valid length/],
    'a length varint past 10 bytes': [frameShadowLayer(Uint8Array.from([0, ...new Array(11).fill(0x80), 0]), { count: n }), n, 'Corrupt', /no valid length/],
    'bytes after the last run': [frameShadowLayer(Uint8Array.from([...runs, 0]), { count: n }), n, 'Corrupt', /1 bytes after/],
    'an empty body for a tile of voxels': [frameShadowLayer(new Uint8Array(0), { count: n }), n, 'Corrupt', /end after 0 of 6/],
    'v2: a run passing n': [frameShadowLayer(Uint8Array.from([4, 0, 6, 255]), { version: 2, count: n }), n, 'Corrupt', /token of 4 at voxel 3 passes/],
    'v2: literals passing n': [frameShadowLayer(Uint8Array.from([4, 0, 7, 1, 2, 3, 4]), { version: 2, count: n }), n, 'Corrupt', /token of 4 at voxel 3 passes/],
    'v2: a token of 2^60 (odd)': [frameShadowLayer(Uint8Array.from([...new Array(8).fill(0xff), 0x0f]), { version: 2, count: n }), n, 'Corrupt', /passes/],
    'v2: literals cut short': [frameShadowLayer(Uint8Array.from([4, 0, 5, 1, 2]), { version: 2, count: n }), n, 'Corrupt', /cut short/],
    'v2: a run without its value': [frameShadowLayer(Uint8Array.from([4, 0, 4]), { version: 2, count: n }), n, 'Corrupt', /no value/],
    'v2: a token varint past 10 bytes': [frameShadowLayer(Uint8Array.from([...new Array(11).fill(0x80), 0]), { version: 2, count: n }), n, 'Corrupt', /no valid length/],
    'v2: tokens ending before n': [frameShadowLayer(Uint8Array.from([4, 0, 2, 9]), { version: 2, count: n }), n, 'Corrupt', /end after 5 of 6/],
    'v2: bytes after the last token': [frameShadowLayer(Uint8Array.from([...shadowTokens(light), 0]), { version: 2, count: n }), n, 'Corrupt', /1 bytes after/],
  };
  for (const [name, [bytes, tileVoxels, code, message]] of Object.entries(cases)) {
    test(name, () => {
      const err = refusal(bytes, tileVoxels);
      assert.equal(err.code, code, err.message);
      assert.match(err.detail, message);
    });
  }

  for (const version of [1, 2]) {
    test(`version ${version}: every truncation and every single-bit flip: a PdagError, or (a flip the CRC does not cover) the same voxels`, () => {
      const light = Uint8Array.from({ length: 600 }, (_, i) => (i % 97 < 40 ? 0 : 200 + ((i * 7) % 5)));
      const valid = encodeShadowLayer(light, { kind: 1, samples: 3, version });
      for (let len = 0; len < valid.length; ++len) refusal(valid.subarray(0, len), 600);
      let decoded = 0;
      for (let bit = 0; bit < valid.length * 8; ++bit) {
        const bytes = valid.slice();
        bytes[bit >> 3] ^= 1 << (bit & 7);
        try {
          const layer = decodeShadowLayer(bytes, 600);
          assert.ok(bit < 64, `a flip of bit ${bit}, inside the CRC's cover, decoded`);
          assert.deepEqual(layer.light, light);
          decoded++;
        } catch (err) {
          if (!(err instanceof PdagError)) throw err;
        }
      }
      // Only the samples (3 -> another count within 1..1440) can change and stay valid: one flip
      // never turns version 1 into 2 (01 -> 10), and a kind flip breaks the samples rule or the kind.
      assert.ok(decoded > 0 && decoded <= 16, `${decoded} flips decoded`);
    });
  }

  test('runs need not be maximal: two runs of one value in a row are read as written', () => {
    const layer = decodeShadowLayer(frameShadowLayer(Uint8Array.from([0, 1, 0, 0, 255, 0]), { count: 4 }), 4);
    assert.deepEqual([...layer.light], [0, 0, 0, 255]);
  });
});
