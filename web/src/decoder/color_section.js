// The colors section (proto/PDAG_FORMAT.md §3), dispatched on its first byte as
// codec/pointdag/color/color_decode.cc DecodeColors does. Raw and the block codecs are read here;
// lossless, the image codecs (png, jpeg, webp, astc) and the hierarchical colors (not random
// access: for files, not the daemon's tiles) are refused as 'Unsupported', as web/wasm refuses them.
import { decodeBlockColors } from './block_colors.js';
import { corrupt, resourceLimit, unsupported } from './pdag_error.js';

export const CODEC_RAW = 0;
export const CODEC_LOSSLESS = 1;
export const CODEC_FIXED3 = 2;
export const CODEC_VBR = 3;
const IMAGE_CODECS = new Set([4, 5, 6, 7]);  // png, jpeg, webp, astc
export const CODEC_HIERARCHICAL = 8;
const MAX_COLORS = 2 ** 32;
// Bit 7 of the first byte (kVoxelColorsOnly in color_codec.h): a mipmap-mode file's section holds
// only the voxels' colors, in Morton order; the internal nodes' are derived, not stored.
export const VOXEL_COLORS_ONLY = 0x80;

// Why this decoder cannot read a colors section with this codec byte, or null when it can.
export function unsupportedColorCodec(codec) {
  if (codec === CODEC_LOSSLESS) return 'lossless (zstd) colors';
  if (IMAGE_CODECS.has(codec)) return `image-mapped colors (codec ${codec}: png, jpeg, webp or astc)`;
  if (codec === CODEC_HIERARCHICAL) return 'hierarchical colors (codec 8)';
  return null;
}

// `count` must come from decoded geometry; `coords`: the voxels' cells in Morton order where the
// colors are one per voxel (leaf mode), else null (block streams of versions 3 and 4 need them).
// -> Uint8Array(3 * count), RGB per color, owned.
export function decodeColors(section, count, coords = null) {
  if (section.length === 0) throw corrupt('colors section is empty');
  if (count === 0) throw corrupt('a colors section for no voxels');
  if (count > MAX_COLORS) throw resourceLimit(`${count} colors are more than a colors section may hold`);
  const codec = section[0] & ~VOXEL_COLORS_ONLY;
  const payload = section.subarray(1);
  if (codec === CODEC_RAW) {
    if (payload.length !== 3 * count) throw corrupt('raw colors do not hold one RGB per voxel');
    return payload.slice();
  }
  if (codec === CODEC_FIXED3 || codec === CODEC_VBR) return decodeBlockColors(payload, count, coords);
  const why = unsupportedColorCodec(codec);
  if (why) throw unsupported(`${why} are not read by this decoder`);
  throw corrupt(`colors section names unknown codec ${codec}`);
}
