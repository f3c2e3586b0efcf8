// Geometry coder 2 (proto/PDAG_FORMAT.md §2.2), read as codec/pointdag/dag/spatial_coder.cc reads
// it, bit for bit: the octree walked level by level in Morton order over the cells the decoder can
// know, each child bit modelled by its known neighbours on its level and its parent's neighbours;
// slots (bricks; from version 5 the nodes of heights 3 and 4 too) coded in full at every occurrence
// and merged here. Returns readSymbols' shape (dag_stream.js).
import { corrupt } from './pdag_error.js';
import { GrowableU32 } from './growable_u32.js';
import { MaskMixer } from './mask_mixer.js';
import { MaskMixer5, PATTERN_BASE } from './mask_mixer5.js';
import { GAMMA_MODELS, RangeDecoder, bitWidth, newModels } from './range_coder.js';
import { mergeBricks, mergeLevel, slotLevel } from './slot_merge.js';
import {
  DIAGONAL_SELF, FACING, PATTERN_COUNT, PATTERN_SELF, POP, SIBLINGS, SIDES, expand, newLevel, planeRecord, planeStates,
  surroundings,
} from './spatial_context.js';

const CLASSES = 22;  // heights 0..21
// Geometry stream version 8 (files' default): version 5 with young flags, lower starting weights, a
// 2-byte header (version; depth in bits 0..4, count mode in bit 5) and no level table.
export const COMPACT_SPATIAL_VERSION = 8;
const MASK_CONTEXTS = 4 * 8 * 27 * 4;
const FLAG_BASE = 0;
const REF_BASE = CLASSES;

// The 8 child bits of cell i, child 0 first; a last bit that must be 1 is implied. `v2`: version
// 2's contexts; `edges`: scratch; `mix`: version 3's and 4's mixer, `mix5` version 5's (null
// before); `planes`: the plane memory's state per child (version 4 on); version 5: `side` and
// `pattern`, scratch for each child's side and pattern bits, `group` the class group times 8.
function decodeMask(rc, young, age, base, lv, i, v2, edges, mix, planes, mix5, side, pattern, group) {
  const o = 6 * i;
  let exists = 0;
  let facing = 0;
  let below = 0;  // version 5: the lower x, y, z face neighbours' masks, a byte each
  for (let axis = 0; axis < 3; ++axis) {
    const lo = lv.nbr[o + 2 * axis];
    if (lo >= 0) {
      exists |= 1 << axis;
      facing |= FACING[axis * 256 + lv.mask[lo]];
      below |= lv.mask[lo] << (8 * axis);
    }
    if (lv.nbr[o + 2 * axis + 1] >= 0) exists |= 8 << axis;
  }
  const sides = exists * 8;
  const around = v2 ? surroundings(lv, i, edges, side, pattern) : 0;
  const most = v2 ? 1 : 3;
  let m = 0;
  let ones = 0;
  for (let c = 0; c < 8; ++c) {
    let bit = 1;
    if (c < 7 || m !== 0) {
      const near = ((facing >>> (4 * c)) & 7) | SIBLINGS[c * 256 + m];
      let extra = 0;
      if (v2) extra = ((around >> c) & 1) * 2 + (((around >> (8 + c)) & 1) | ((m & DIAGONAL_SELF[c]) !== 0));
      const model = base + ((ones * 8 + near) * 27 + SIDES[sides + c]) * 4 + extra;
      if (mix5) {
        const lower2 = ((below >> c) & 1) | ((below >> (7 + c)) & 2) | ((below >> (14 + c)) & 4);
        const index = PATTERN_BASE[group + c] + (pattern[c] | PATTERN_SELF[c * 256 + m] | (lower2 << PATTERN_COUNT[c]));
        bit = mix5.bit(rc, young, age, model, c, m, ones > 0, exists, planes[c], index, side[c], ((c * 8 + near) * 8 + lower2) * 4 + extra);
      } else if (mix) {
        bit = mix.bit(rc, young, age, model, c, m, lv.parent[i], near, ones > 0, exists, planes[c]);
      } else {
        bit = rc.youngBit(young, age, model);
      }
    }
    m |= bit << c;
    if (ones < most) ones += bit;
  }
  return m;
}

// Version 8's whole stream: returns decodeSpatial's shape with the count mode.
export function decodeCompactSpatial(bytes, maxNodes) {
  if (bytes.length < 2) throw corrupt('geometry stream is shorter than its 2-byte header');
  const depth = bytes[1] & 31;
  if (depth < 2 || depth > CLASSES - 1) throw corrupt(`geometry stream depth ${depth} is outside 2..21`);
  if (bytes[1] >> 6 !== 0) throw corrupt('geometry stream sets reserved header bits');
  const rc = new RangeDecoder(bytes, 2, bytes.length, true);
  return { ...decodeSpatial(rc, depth, null, COMPACT_SPATIAL_VERSION, maxNodes), mode: bytes[1] >> 5 };
}

// `counts`: the level table (null in version 8, whose nodes `maxNodes` bounds as they are decoded).
export function decodeSpatial(rc, depth, counts, version, maxNodes) {
  const levels = depth - 2;
  const v2 = version >= 2;
  const edges = new Int32Array(12);
  const mix5 = version >= 5 ? new MaskMixer5(version) : null;
  const mix = version >= 3 && !mix5 ? new MaskMixer(version >= 4) : null;
  const side = mix5 ? new Uint8Array(8) : null;
  const pattern = mix5 ? new Uint16Array(8) : null;
  const slotsFrom = slotLevel(levels, version);
  const planes = version >= 4;
  const last = [null, null, null];
  const states = new Uint8Array(8);
  const young = newModels(CLASSES * MASK_CONTEXTS);
  const age = new Uint8Array(CLASSES * MASK_CONTEXTS);
  const p = newModels(REF_BASE + CLASSES * GAMMA_MODELS);
  const youngFlags = version >= 8;
  const flagAge = youngFlags ? new Uint8Array(CLASSES) : null;  // young flags: models FLAG_BASE + height of p
  let nodes = 1;  // on the levels above the slots, the root included
  let nodesHere = 1;  // first cells of this level: the new nodes the level above referenced
  const masks = [];
  const firstChild = [];
  const children = [];
  let slotLo = new Uint32Array(levels === 0 ? 1 : 0);
  let slotHi = new Uint32Array(levels === 0 ? 1 : 0);
  let cur = newLevel(1, planes);
  cur.first[0] = 1;
  cur.nbr.fill(-1);
  for (let level = 0; level < depth; ++level) {
    const height = depth - level;
    const maskBase = height * MASK_CONTEXTS;
    const flagModel = FLAG_BASE + height;
    const refBase = REF_BASE + height * GAMMA_MODELS;
    const internal = level < levels;
    // On a slot level every cell is first: as many nodes as cells, merged after the walk.
    const n = !internal ? 0 : level >= slotsFrom ? cur.n : nodesHere;
    const group = 8 * (height <= 1 ? 0 : height === 2 ? 1 : 2);
    const levelMasks = new Uint8Array(n);
    const first = new Uint32Array(n + 1);
    const kids = new GrowableU32(internal && level + 1 < levels ? Math.min(8 * n, 2 * (counts ? counts[level + 1] : n)) : 0);
    if (planes) for (let axis = 0; axis < 3; ++axis) last[axis] = new Uint8Array(2 << level);
    let coded = 0;
    let seen = 0;
    let slots = 0;
    for (let i = 0; i < cur.n; ++i) {
      const id = cur.id[i];
      if (!cur.first[i]) {
        cur.mask[i] = internal ? levelMasks[id] : level > levels ? cellByte(slotLo, slotHi, id) : cellMask(slotLo[id], slotHi[id]);
        continue;
      }
      if (planes) planeStates(last, cur.pos, i, states);
      const mask = decodeMask(rc, young, age, maskBase, cur, i, v2, edges, mix, states, mix5, side, pattern, group);
      cur.mask[i] = mask;
      if (planes) planeRecord(last, cur.pos, i, mask);
      if (level > levels) {
        const s = id >>> 3;
        const c = id & 7;
        if (c < 4) slotLo[s] |= mask << (8 * c);
        else slotHi[s] |= mask << (8 * (c - 4));
      }
      if (!internal) continue;
      levelMasks[coded] = mask;
      const count = POP[mask];
      if (level + 1 === levels) {  // brick slots
        first[coded++] = slots;
        cur.kids[i] = slots;
        slots += count;
        continue;
      }
      first[coded++] = kids.n;
      cur.kids[i] = kids.n;
      if (level + 1 >= slotsFrom) {  // slots of an internal level: new nodes, numbered in order
        for (let c = 0; c < count; ++c) kids.push(seen++);
        continue;
      }
      for (let c = count; c > 0; --c) {
        let k;
        if (seen > 0 && (youngFlags ? rc.youngBit(p, flagAge, flagModel) : rc.bit(p, flagModel))) {
          k = rc.gamma(p, refBase, bitWidth(seen)) - 1;
          if (k >= seen) throw corrupt('geometry stream refers to a node not yet seen');
        } else {
          k = seen++;
          if (counts && seen > counts[level + 1]) throw corrupt('geometry stream holds more nodes than its header declares');
          if (++nodes > maxNodes) throw corrupt('geometry stream holds more nodes than its voxels allow');
        }
        kids.push(k);
      }
    }
    if (rc.overrun()) throw corrupt('geometry stream ends early');
    if (counts && level + 1 < slotsFrom && seen !== counts[level + 1]) throw corrupt('geometry stream holds fewer nodes than its header declares');
    nodesHere = seen;
    if (internal) {
      first[n] = level + 1 === levels ? slots : kids.n;
      masks.push(levelMasks);
      firstChild.push(first);
      children.push(kids.done());
      if (level + 1 === levels) {
        slotLo = new Uint32Array(slots);
        slotHi = new Uint32Array(slots);
      }
    }
    if (level + 1 < depth) cur = expand(cur, level, levels, kids.a, planes);
  }
  const merged = mergeBricks(slotLo, slotHi, counts ? counts[levels] : null);
  if (levels > 0) children[levels - 1] = merged.ids;
  for (let level = levels - 1; level >= slotsFrom; --level) {
    const unique = mergeLevel(masks[level], children[level], counts ? counts[level] : null);
    masks[level] = unique.masks;
    firstChild[level] = unique.first;
    children[level] = unique.kids;
    const above = children[level - 1];
    for (let k = 0; k < above.length; ++k) above[k] = unique.ids[above[k]];
  }
  let total = merged.brickLo.length;
  for (const m of masks) total += m.length;
  if (total > maxNodes) throw corrupt('geometry stream holds more nodes than its voxels allow');
  return { depth, levels, masks, firstChild, children, brickLo: merged.brickLo, brickHi: merged.brickHi };
}

function cellByte(lo, hi, id) {
  const s = id >>> 3;
  const c = id & 7;
  return (c < 4 ? lo[s] >>> (8 * c) : hi[s] >>> (8 * (c - 4))) & 0xff;
}

function cellMask(lo, hi) {
  let cells = 0;
  for (let c = 0; c < 4; ++c) {
    if ((lo >>> (8 * c)) & 0xff) cells |= 1 << c;
    if ((hi >>> (8 * c)) & 0xff) cells |= 1 << (c + 4);
  }
  return cells;
}
