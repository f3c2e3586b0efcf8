// The block color streams "fixed3" and "vbr" (proto/PDAG_FORMAT.md §3), read as
// codec/pointdag/color/block_decoder.cc BlockColorDecoder::Open reads them, with the same checks in
// the same order, straight into RGB bytes (DecodeAll's result). The output grows with the blocks
// really decoded, so a stream that lies about its count fails before it costs memory.
import { corrupt } from './pdag_error.js';
import { GAMMA_MODELS, RangeDecoder, bitTreeModels, newModels, unZigZag } from './range_coder.js';
import { readVarint } from './varint.js';
import { WeightContexts, SPATIAL_WEIGHT_CONTEXTS } from './weight_contexts.js';
import { WeightMixer } from './weight_mixer.js';
import { PrefixDecoder } from './prefix_code.js';
import { readWeightGroups } from './weight_groups.js';

// Versions 1 to 4 and 6 (tiles: weights in groups, weight_groups.js); 5 was never released.
const STREAM_VERSION = 6;
const MIXED_VERSION = 4;
const FIXED_WEIGHT_CODES_VERSION = 6;
const hasSpatialContexts = (version) => version === 3 || version === MIXED_VERSION;
const LAYOUT_FIXED = 1;
const LAYOUT_VARIABLE = 2;
const FIXED_BITS = 3;
const MAX_WEIGHT_BITS = 4;
const MACRO_BLOCK = 16384;
const LENGTH_BITS = 15;      // bit width of MACRO_BLOCK

// BlockModels of block_stream.h, flattened.
const WIDTHS = MAX_WEIGHT_BITS + 1;
const LENGTH_BASE = 0;
const WIDTH_BASE = LENGTH_BASE + WIDTHS * GAMMA_MODELS;
const A_BASE = WIDTH_BASE + WIDTHS * bitTreeModels(3);
const A_NEAR_BASE = A_BASE + 3 * GAMMA_MODELS;  // version 4: A predicted from the block's neighbours
const B_BASE = A_NEAR_BASE + 3 * GAMMA_MODELS;
const WEIGHT_BASE = B_BASE + WIDTHS * 3 * GAMMA_MODELS;
const WEIGHT_TREE = bitTreeModels(MAX_WEIGHT_BITS);
// Per width: 17 previous weights (16 = first of a block) in versions 1 and 2, 33 spatial contexts in 3.
const WEIGHT_CONTEXTS = SPATIAL_WEIGHT_CONTEXTS;
const MODEL_COUNT = WEIGHT_BASE + WIDTHS * WEIGHT_CONTEXTS * WEIGHT_TREE;

const clampByte = (v) => (v < 0 ? 0 : v > 255 ? 255 : v);

// `stored`: the stream after the section's codec byte; `expectedCount` from decoded geometry;
// `coords`: the voxels' cells (x, y, z per voxel in Morton order) where the colors are one per voxel
// (leaf mode), else null; version 3 and 4 streams need them. -> Uint8Array(3 * expectedCount), RGB per color.
export function decodeBlockColors(stored, expectedCount, coords = null) {
  if (stored.length < 4) throw corrupt('color stream is shorter than its header');
  if (stored[0] < 1 || stored[0] > STREAM_VERSION || stored[0] === 5) throw corrupt(`color stream version ${stored[0]} is unknown`);
  // DifferenceCode of block_stream.h: version 2 codes (dG, dR - dG, dB - dG), version 1 (dR, dG, dB).
  const decorrelated = stored[0] >= 2;
  const differenceBits = decorrelated ? 10 : 9;
  const layout = stored[1];
  if (layout !== LAYOUT_FIXED && layout !== LAYOUT_VARIABLE) throw corrupt('color stream layout is unknown');
  const cursor = { pos: 4 };
  const count = readVarint(stored, cursor);
  const blocks = count < 0 ? -1 : readVarint(stored, cursor);
  const payloadSize = blocks < 0 ? -1 : readVarint(stored, cursor);
  if (payloadSize < 0) throw corrupt('color stream header is cut short');
  if (payloadSize !== stored.length - cursor.pos) throw corrupt('color stream is not as long as its header says');
  if (count !== expectedCount) throw corrupt(`color stream holds ${count} colors, expected ${expectedCount}`);
  if (count > 0xffffffff || blocks > count || (count > 0 && blocks === 0)) throw corrupt('color stream block count is impossible');
  const spatialContexts = hasSpatialContexts(stored[0]);
  if (spatialContexts && (coords === null || coords.length !== 3 * count)) {
    throw corrupt("color stream has spatial contexts, but there are no voxels' Morton codes for them");
  }
  // No block codes more than a macro block of colors per byte of payload.
  if (Math.floor(count / MACRO_BLOCK) > payloadSize + 8) {
    throw corrupt(`color stream declares ${count} colors, more than its ${payloadSize} bytes can hold`);
  }

  const mixed = stored[0] === MIXED_VERSION;
  const grouped = stored[0] === FIXED_WEIGHT_CODES_VERSION;
  const spatial = spatialContexts ? new WeightContexts(coords) : null;
  const mixer = mixed ? new WeightMixer() : null;
  const near = new Int32Array(4);  // the block's surroundings: weighted R, G, B sums and weight
  const p = newModels(MODEL_COUNT);
  // Version 6: the range-coded section's length, the section, then the weights' groups.
  let rangedEnd = stored.length;
  if (grouped) {
    const ranged = readVarint(stored, cursor);
    if (ranged < 0) throw corrupt('color stream ends inside its section length');
    if (ranged > stored.length - cursor.pos) throw corrupt('color stream is shorter than its section length says');
    rangedEnd = cursor.pos + ranged;
  }
  const rc = new RangeDecoder(stored, cursor.pos, rangedEnd);
  const groups = grouped ? new PrefixDecoder(stored, rangedEnd, stored.length) : null;
  const blockWeights = grouped ? new Uint8Array(MACRO_BLOCK) : null;
  let out = new Uint8Array(3 * Math.min(count, 4 * MACRO_BLOCK));
  const palette = new Uint8Array(3 * 16);
  let next = 0;
  let prevBits = 0;
  let pr = 0, pg = 0, pb = 0;
  for (let k = 0; k < blocks; ++k) {
    const length = rc.gamma(p, LENGTH_BASE + prevBits * GAMMA_MODELS, LENGTH_BITS);
    const bits = layout === LAYOUT_VARIABLE ? rc.bitTree(p, WIDTH_BASE + prevBits * 8, 3) : FIXED_BITS;
    if (bits > MAX_WEIGHT_BITS) throw corrupt('color block has more than 4 bits per weight');
    if (length === 0 || length > count - next) throw corrupt('color block length is impossible');
    if (Math.floor(next / MACRO_BLOCK) !== Math.floor((next + length - 1) / MACRO_BLOCK)) throw corrupt('color block crosses a macro block');
    // Endpoint differences: A from a base (the previous block's A, or in version 4 the prediction
    // from the block's neighbours), B from A, as (dG, dR - dG, dB - dG) from version 2 on.
    let ar = pr, ag = pg, ab = pb, sr = 0, sg = 0, sb = 0;  // A's base, then A; B - A
    const readSpan = () => {
      const base = B_BASE + bits * 3 * GAMMA_MODELS;
      const d0 = unZigZag(rc.gamma(p, base, differenceBits));
      const d1 = unZigZag(rc.gamma(p, base + GAMMA_MODELS, differenceBits));
      const d2 = unZigZag(rc.gamma(p, base + 2 * GAMMA_MODELS, differenceBits));
      sr = decorrelated ? d1 + d0 : d0;
      sg = decorrelated ? d0 : d1;
      sb = decorrelated ? d2 + d0 : d2;
    };
    let aBase = A_BASE;
    if (mixed) {
      if (bits) readSpan();
      spatial.surroundings(next, length, out, near);
      if (near[3] > 0) {
        // PredictA in block_stream.h: the neighbours' mean less half of B - A (toward zero), clamped.
        const half = near[3] >> 1;
        ar = clampByte(Math.floor((near[0] + half) / near[3]) - Math.trunc(sr / 2));
        ag = clampByte(Math.floor((near[1] + half) / near[3]) - Math.trunc(sg / 2));
        ab = clampByte(Math.floor((near[2] + half) / near[3]) - Math.trunc(sb / 2));
        aBase = A_NEAR_BASE;
      }
    }
    const d0 = unZigZag(rc.gamma(p, aBase, differenceBits));
    const d1 = unZigZag(rc.gamma(p, aBase + GAMMA_MODELS, differenceBits));
    const d2 = unZigZag(rc.gamma(p, aBase + 2 * GAMMA_MODELS, differenceBits));
    ar += decorrelated ? d1 + d0 : d0;
    ag += decorrelated ? d0 : d1;
    ab += decorrelated ? d2 + d0 : d2;
    if (bits && !mixed) readSpan();
    const br = ar + sr, bg = ag + sg, bb = ab + sb;
    if ((ar | ag | ab | br | bg | bb) & ~0xff) throw corrupt('color block endpoint outside 0..255');
    if (3 * (next + length) > out.length) {
      const bigger = new Uint8Array(3 * Math.min(count, Math.max(2 * (out.length / 3), next + length)));
      bigger.set(out);
      out = bigger;
    }
    let o = 3 * next;
    if (bits === 0) {
      for (let i = 0; i < length; ++i, o += 3) {
        out[o] = ar;
        out[o + 1] = ag;
        out[o + 2] = ab;
      }
    } else {
      // Every color of the block is one of m + 1 mixes of its endpoints (Interpolate in block_fit.h).
      const m = (1 << bits) - 1;
      for (let w = 0; w <= m; ++w) {
        palette[3 * w] = ((ar * (m - w) + br * w + (m >> 1)) / m) | 0;
        palette[3 * w + 1] = ((ag * (m - w) + bg * w + (m >> 1)) / m) | 0;
        palette[3 * w + 2] = ((ab * (m - w) + bb * w + (m >> 1)) / m) | 0;
      }
      const wBase = WEIGHT_BASE + bits * WEIGHT_CONTEXTS * WEIGHT_TREE;
      if (grouped) readWeightGroups(groups, bits, length, blockWeights);
      let prevW = 16;
      for (let i = 0; i < length; ++i, o += 3) {
        let w;
        if (grouped) {
          w = blockWeights[i];
        } else if (mixed) {
          w = mixer.decode(rc, bits, spatial.position(next + i, out, ar, ag, ab, br, bg, bb, bits, true), prevW);
        } else {
          const context = spatial ? spatial.of(next + i, out, ar, ag, ab, br, bg, bb, bits, prevW) : prevW;
          w = rc.bitTree(p, wBase + context * WEIGHT_TREE, bits);
        }
        out[o] = palette[3 * w];
        out[o + 1] = palette[3 * w + 1];
        out[o + 2] = palette[3 * w + 2];
        prevW = w;
      }
    }
    if (rc.overrun() || (grouped && groups.overrun())) throw corrupt('color stream is cut short');
    next += length;
    prevBits = bits;
    pr = ar;
    pg = ag;
    pb = ab;
  }
  if (next !== count) throw corrupt('color blocks do not cover every color');
  return out;
}
