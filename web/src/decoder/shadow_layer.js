// decodeShadowLayer(bytes, tileVoxels): a tile's shadow layer (GET /v1/datasets/{id}/shadows/tiles/...,
// proto/SHADOW_FORMAT.md §2) -> {kind, samples, count, light: Uint8Array(count)}, one byte of light per
// voxel in the tile's Morton order (0 = shadowed, 255 = lit at every sample). Version 1 codes the
// light as runs, version 2 as runs and literal stretches; runs need not be maximal.
// Every malformed layer throws PdagError (the decoders' one error type): 'Corrupt' for bytes that
// contradict the format, 'Unsupported' for another version. The light array is sized by
// `tileVoxels`, the count the tile's own hierarchy entry gives, never by the layer's header alone.
import { crc32c } from './crc32c.js';
import { corrupt, unsupported } from './pdag_error.js';
import { readVarint } from './varint.js';

export const SHADOW_KIND_DIRECTION = 0;
export const SHADOW_KIND_SUN_HOURS = 1;
export const MAX_SHADOW_SAMPLES = 1440;
const HEADER_BYTES = 16;
const MAGIC = [0x50, 0x44, 0x53, 0x48]; // "PDSH"

export function decodeShadowLayer(bytes, tileVoxels) {
  if (!(bytes instanceof Uint8Array)) bytes = new Uint8Array(bytes);
  if (bytes.length < HEADER_BYTES) throw corrupt(`shadow layer of ${bytes.length} bytes, shorter than its 16-byte header`);
  if (MAGIC.some((b, i) => bytes[i] !== b)) throw corrupt('shadow layer without its PDSH magic');
  const version = bytes[4];
  if (version !== 1 && version !== 2) throw unsupported(`shadow layer version ${version}; this decoder reads versions 1 and 2`);
  const kind = bytes[5];
  if (kind !== SHADOW_KIND_DIRECTION && kind !== SHADOW_KIND_SUN_HOURS) throw corrupt(`shadow layer of unknown kind ${kind}`);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const samples = view.getUint16(6, true);
  if (samples < 1 || samples > MAX_SHADOW_SAMPLES) throw corrupt(`shadow layer with ${samples} samples, outside 1..${MAX_SHADOW_SAMPLES}`);
  if (kind === SHADOW_KIND_DIRECTION && samples !== 1) throw corrupt(`shadow layer of one light with ${samples} samples`);
  const count = view.getUint32(8, true);
  if (count === 0) throw corrupt('shadow layer of no voxels');
  if (count !== tileVoxels) throw corrupt(`shadow layer of ${count} voxels for a tile of ${tileVoxels}`);
  if (crc32c(bytes.subarray(HEADER_BYTES)) !== view.getUint32(12, true)) throw corrupt('shadow layer CRC-32C mismatch');

  const light = new Uint8Array(count);
  const end = version === 1 ? readRuns(bytes, light) : readTokens(bytes, light);
  if (end !== bytes.length) throw corrupt(`shadow layer has ${bytes.length - end} bytes after its last run`);
  return { kind, samples, count, light };
}

// Version 1: `value` then `length - 1` (varint) per run, until the tile's voxels are covered.
// Returns where the runs end.
function readRuns(bytes, light) {
  const n = light.length;
  const cursor = { pos: HEADER_BYTES };
  for (let filled = 0; filled < n;) {
    if (cursor.pos >= bytes.length) throw corrupt(`shadow layer runs end after ${filled} of ${n} voxels`);
    const value = bytes[cursor.pos++];
    const lengthMinusOne = readVarint(bytes, cursor);
    if (lengthMinusOne < 0) throw corrupt(`shadow layer run at voxel ${filled} has no valid length`);
    if (lengthMinusOne >= n - filled) throw corrupt(`shadow layer run of ${lengthMinusOne + 1} at voxel ${filled} passes ${n} voxels`);
    light.fill(value, filled, filled + lengthMinusOne + 1);
    filled += lengthMinusOne + 1;
  }
  return cursor.pos;
}

// Version 2: a varint token t per stretch: t even, a run of t/2 + 1 copies of the next byte; t odd,
// (t - 1)/2 + 1 literal bytes follow. Returns where the tokens end.
function readTokens(bytes, light) {
  const n = light.length;
  const cursor = { pos: HEADER_BYTES };
  for (let filled = 0; filled < n;) {
    if (cursor.pos >= bytes.length) throw corrupt(`shadow layer runs end after ${filled} of ${n} voxels`);
    const token = readVarint(bytes, cursor);
    if (token < 0) throw corrupt(`shadow layer token at voxel ${filled} has no valid length`);
    // Compared before the parity is read: a token past 2^53 is refused here whatever its low bit.
    if (token >= 2 * (n - filled)) throw corrupt(`shadow layer token of ${Math.floor(token / 2) + 1} at voxel ${filled} passes ${n} voxels`);
    const length = Math.floor(token / 2) + 1;
    if (token % 2 === 0) {
      if (cursor.pos >= bytes.length) throw corrupt(`shadow layer run at voxel ${filled} has no value`);
      light.fill(bytes[cursor.pos++], filled, filled + length);
    } else {
      if (cursor.pos + length > bytes.length) throw corrupt(`shadow layer literals at voxel ${filled} are cut short`);
      light.set(bytes.subarray(cursor.pos, cursor.pos + length), filled);
      cursor.pos += length;
    }
    filled += length;
  }
  return cursor.pos;
}
