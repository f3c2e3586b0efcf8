// decodeShadowLayer(bytes, tileVoxels): a tile's shadow layer (GET /v1/datasets/{id}/shadows/tiles/...,
// proto/SHADOW_FORMAT.md §2) -> {kind, samples, count, light: Uint8Array(count)}, one byte of light per
// voxel in the tile's Morton order (0 = shadowed, 255 = lit at every sample). Runs need not be maximal.
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
const VERSION = 1;
const MAGIC = [0x50, 0x44, 0x53, 0x48]; // "PDSH"

export function decodeShadowLayer(bytes, tileVoxels) {
  if (!(bytes instanceof Uint8Array)) bytes = new Uint8Array(bytes);
  if (bytes.length < HEADER_BYTES) throw corrupt(`shadow layer of ${bytes.length} bytes, shorter than its 16-byte header`);
  if (MAGIC.some((b, i) => bytes[i] !== b)) throw corrupt('shadow layer without its PDSH magic');
  if (bytes[4] !== VERSION) throw unsupported(`shadow layer version ${bytes[4]}; this decoder reads version ${VERSION}`);
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
  const cursor = { pos: HEADER_BYTES };
  let filled = 0;
  while (filled < count) {
    if (cursor.pos >= bytes.length) throw corrupt(`shadow layer runs end after ${filled} of ${count} voxels`);
    const value = bytes[cursor.pos++];
    const lengthMinusOne = readVarint(bytes, cursor);
    if (lengthMinusOne < 0) throw corrupt(`shadow layer run at voxel ${filled} has no valid length`);
    if (lengthMinusOne >= count - filled) throw corrupt(`shadow layer run of ${lengthMinusOne + 1} at voxel ${filled} passes ${count} voxels`);
    light.fill(value, filled, filled + lengthMinusOne + 1);
    filled += lengthMinusOne + 1;
  }
  if (cursor.pos !== bytes.length) throw corrupt(`shadow layer has ${bytes.length - cursor.pos} bytes after its last run`);
  return { kind, samples, count, light };
}
