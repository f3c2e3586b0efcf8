// The decode worker's protocol (contract 2): replies, transferred buffers, errors, the backends and
// the fallback when the WebAssembly build cannot load; and decode_worker.js itself under a minimal
// stand-in of a worker's globals.
import assert from 'node:assert/strict';
import { pathToFileURL } from 'node:url';
import { before, describe, test } from 'node:test';

import { DEFAULT_BACKEND, DecodeService } from '../../web/src/decoder/decode_service.js';
import { decodePdag } from '../../web/src/decoder/decode_pdag.js';
import { WASM_SKIPPED, config } from './lib/config.mjs';
import { denseCube, framePdag, utf8, writeGeometry } from './lib/pdag_writer.mjs';

// A depth-3 solid cube in mipmap mode with raw colors for its 585 nodes (the root, then 8 bricks of
// 1 + 8 cells + 64 voxels each, in pre-order): color i = (i, 2i, 3i) mod 256.
function cubeTile() {
  const colors = new Uint8Array(3 * 585);
  for (let i = 0; i < 585; ++i) colors.set([i & 255, (2 * i) & 255, (3 * i) & 255], 3 * i);
  return framePdag([
    ['meta', utf8(JSON.stringify({ voxels: 512, depth: 3, voxel_size: 0.25, origin: [1, 2, 3] }))],
    ['geometry', writeGeometry(denseCube(3, 1))],
    ['colors', new Uint8Array([0, ...colors])],
  ]);
}

const wasmFactory = () => import(config.wasmDecoder).then((m) => m.default);
const failingFactory = () => Promise.reject(new Error('no such module'));

describe('decode worker', () => {
  let tile;
  before(() => { tile = cubeTile(); });

  test('replies with the voxels, their buffers to transfer, and the decode time', async () => {
    const want = decodePdag(tile);
    const { reply, transfer } = await new DecodeService(failingFactory, 'js').handle({ id: 7, bytes: tile.slice().buffer });
    assert.equal(reply.id, 7);
    assert.equal(reply.ok, true);
    assert.equal(reply.backend, 'js');
    assert.equal(reply.count, 512);
    assert.equal(reply.depth, 3);
    assert.equal(reply.voxelSize, 0.25);
    assert.deepEqual(reply.origin, [1, 2, 3]);
    assert.deepEqual(reply.coords, want.coords);
    assert.deepEqual(reply.colors, want.colors);
    // Voxel 0 has pre-order rank 3: after the root, its brick and its cell.
    assert.deepEqual([...reply.colors.subarray(0, 3)], [3, 6, 9]);
    assert.ok(reply.decodeMs >= 0);
    assert.deepEqual(transfer, [reply.coords.buffer, reply.colors.buffer]);
  });

  test('errors are replies, with the PdagError code', async () => {
    const service = new DecodeService(failingFactory);
    const bad = await service.handle({ id: 1, bytes: tile.slice(0, 40).buffer });
    assert.deepEqual({ ...bad.reply, error: undefined }, { id: 1, ok: false, error: undefined, code: 'Corrupt' });
    assert.match(bad.reply.error, /^Corrupt: \.pdag ends inside its section table/);
    const unknown = await service.handle({ id: 2, bytes: tile.slice().buffer, backend: 'gpu' });
    assert.match(unknown.reply.error, /unknown decoder backend 'gpu'/);
  });

  test('an explicit wasm request fails when the build cannot load; the default falls back to js', async () => {
    const explicit = await new DecodeService(failingFactory).handle({ id: 3, bytes: tile.slice().buffer, backend: 'wasm' });
    assert.equal(explicit.reply.ok, false);
    assert.match(explicit.reply.error, /WebAssembly decoder does not load: no such module/);
    assert.equal(DEFAULT_BACKEND, 'wasm');
    const service = new DecodeService(failingFactory);
    const fallback = await service.handle({ id: 4, bytes: tile.slice().buffer });
    assert.equal(fallback.reply.ok, true);
    assert.equal(fallback.reply.backend, 'js');
  });

  test('the wasm backend gives the same reply', async (t) => {
    if (!config.wasmDecoder) return t.skip(WASM_SKIPPED);
    const service = new DecodeService(wasmFactory);
    const js = (await service.handle({ id: 5, bytes: tile.slice().buffer, backend: 'js' })).reply;
    const wasm = (await service.handle({ id: 5, bytes: tile.slice().buffer, backend: 'wasm' })).reply;
    assert.equal(wasm.backend, 'wasm');
    assert.deepEqual({ ...wasm, backend: 'js', decodeMs: 0 }, { ...js, decodeMs: 0 });
  });

  test('decode_worker.js answers postMessage', async (t) => {
    const posted = [];
    const glue = config.wasmDecoder ? `?wasm=${encodeURIComponent(pathToFileURL(config.wasmDecoder).href)}` : '';
    globalThis.self = { location: { href: `file:///worker.js${glue}` }, postMessage: (m, transfer) => posted.push({ m, transfer }) };
    await import('../../web/src/decoder/decode_worker.js');
    await globalThis.self.onmessage({ data: { id: 9, bytes: tile.slice().buffer, backend: 'js' } });
    assert.equal(posted[0].m.ok, true);
    assert.equal(posted[0].m.count, 512);
    assert.equal(posted[0].transfer.length, 2);
    if (!config.wasmDecoder) return t.skip(WASM_SKIPPED);
    await globalThis.self.onmessage({ data: { id: 10, bytes: tile.slice().buffer, backend: 'wasm' } });
    assert.equal(posted[1].m.backend, 'wasm');
    assert.deepEqual(posted[1].m.coords, posted[0].m.coords);
  });
});
