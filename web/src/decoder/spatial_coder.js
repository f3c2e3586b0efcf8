// Geometry coder 2 (proto/PDAG_FORMAT.md §2.2), read as codec/pointdag/dag/spatial_coder.cc reads
// it, bit for bit: the octree walked level by level in Morton order over the cells the decoder can
// know, each child bit modelled by its known neighbours on its level and its parent's neighbours;
// bricks coded in full at every slot and merged here. Returns readSymbols' shape (dag_stream.js).
import { corrupt } from './pdag_error.js';
import { GrowableU32 } from './growable_u32.js';
import { MaskMixer } from './mask_mixer.js';
import { GAMMA_MODELS, bitWidth, newModels } from './range_coder.js';

const CLASSES = 22;  // heights 0..21
const MASK_CONTEXTS = 4 * 8 * 27 * 4;
const FLAG_BASE = 0;
const REF_BASE = CLASSES;
const POP = Uint8Array.from({ length: 256 }, (_, i) => {
  let n = 0;
  for (let v = i; v; v &= v - 1) ++n;
  return n;
});
const rank = (mask, bit) => POP[mask & ((1 << bit) - 1)];

// Cells 0..n−1 and a sentinel row n (no neighbours, mask 0) that version 2's lookups go through;
// `positions`: x, y, z per cell (version 4's plane memory).
function newLevel(n, positions) {
  const nbr = new Int32Array(6 * (n + 1));
  nbr.fill(-1, 6 * n);
  return { n, id: new Uint32Array(n), first: new Uint8Array(n), parent: new Uint8Array(n), nbr, mask: new Uint8Array(n + 1), kids: new Uint32Array(n), pos: new Uint32Array(positions ? 3 * n : 0) };
}

// Version 4's plane memory, as spatial_coder.cc's PlaneMemory: per axis and plane of the next level,
// 0 = no cell spanning it coded yet, 1 = the last one had no children there, 2 = it had.
const LOW_HALF = [0x0f, 0x33, 0x55];
function planeStates(last, pos, i, out) {
  const x = 2 * pos[3 * i];
  const y = 2 * pos[3 * i + 1];
  const z = 2 * pos[3 * i + 2];
  const x0 = 9 * last[0][x], x1 = 9 * last[0][x + 1];
  const y0 = 3 * last[1][y], y1 = 3 * last[1][y + 1];
  const z0 = last[2][z], z1 = last[2][z + 1];
  out[0] = x0 + y0 + z0;
  out[1] = x0 + y0 + z1;
  out[2] = x0 + y1 + z0;
  out[3] = x0 + y1 + z1;
  out[4] = x1 + y0 + z0;
  out[5] = x1 + y0 + z1;
  out[6] = x1 + y1 + z0;
  out[7] = x1 + y1 + z1;
}
function planeRecord(last, pos, i, mask) {
  for (let axis = 0; axis < 3; ++axis) {
    const p = 2 * pos[3 * i + axis];
    last[axis][p] = mask & LOW_HALF[axis] ? 2 : 1;
    last[axis][p + 1] = mask & ~LOW_HALF[axis] & 0xff ? 2 : 1;
  }
}

// The context's parts as tables, as spatial_coder.cc builds them: SIDES[exists * 8 + c] (exists =
// upper << 3 | lower neighbours present), SIBLINGS[c * 256 + m], FACING[axis * 256 + mask] (4 bits a child).
const SIDES = new Uint8Array(64 * 8);
const SIBLINGS = new Uint8Array(8 * 256);
const FACING = new Uint32Array(3 * 256);
for (let e = 0; e < 64; ++e) {
  for (let c = 0; c < 8; ++c) {
    let sides = 0;
    for (let axis = 0; axis < 3; ++axis) {
      const up = (e >> (3 + axis)) & 1;
      const down = (e >> axis) & 1;
      const outer = c & (4 >> axis) ? up : down;
      const opposite = c & (4 >> axis) ? down : up;
      sides = sides * 3 + (outer ? 2 : opposite ? 1 : 0);
    }
    SIDES[e * 8 + c] = sides;
  }
}
for (let c = 0; c < 8; ++c) {
  for (let m = 0; m < 256; ++m) {
    for (let axis = 0; axis < 3; ++axis) {
      if (c & (4 >> axis)) SIBLINGS[c * 256 + m] |= ((m >> (c ^ (4 >> axis))) & 1) << axis;
    }
  }
}
for (let axis = 0; axis < 3; ++axis) {
  const a = 4 >> axis;
  for (let m = 0; m < 256; ++m) {
    let t = 0;
    for (let c = 0; c < 8; ++c) if (!(c & a)) t |= (((m >> (c | a)) & 1) << axis) << (4 * c);
    FACING[axis * 256 + m] = t >>> 0;
  }
}

// Child c's lower diagonal neighbours on its level (offsets −1 on the axes of 6, 5, 3, 7), as
// spatial_coder.cc's tables: DIAGONAL_FROM[p * 256 + mask] (bit c: one lies in the cell at parent
// offset p != 0 and is set), DIAGONAL_SELF[c] (the bits of the mask so far that are such neighbours).
const DIAGONAL_FROM = new Uint8Array(8 * 256);
const DIAGONAL_SELF = new Uint8Array(8);
for (let c = 0; c < 8; ++c) {
  for (const o of [6, 5, 3, 7]) {
    const p = o & ~c;
    if (p === 0) DIAGONAL_SELF[c] |= 1 << (c ^ o);
    else for (let m = 0; m < 256; ++m) if ((m >> (c ^ o)) & 1) DIAGONAL_FROM[p * 256 + m] |= 1 << c;
  }
}

// Version 2's view beyond the faces, as spatial_coder.cc's Surroundings (through the sentinel row
// `none`): returns outer (bits 0..7: at least 2 of octant c's 3 edge and 1 corner neighbours exist)
// | diagonal << 8 (bit c: a lower diagonal neighbour of child c outside the cell is set).
function surroundings(lv, i, edges) {
  const nbr = lv.nbr;
  const none = lv.n;
  const o = 6 * i;
  for (let a = 0; a < 2; ++a) {
    for (let b = 0; b < 2; ++b) {
      edges[a * 2 + b] = edge(nbr, none, o, a, 2 + b);
      edges[4 + a * 2 + b] = edge(nbr, none, o, a, 4 + b);
      edges[8 + a * 2 + b] = edge(nbr, none, o, 2 + a, 4 + b);
    }
  }
  let outer = 0;
  let lowerCorner = -1;
  for (let c = 0; c < 8; ++c) {
    const x = (c >> 2) & 1;
    const y = (c >> 1) & 1;
    const z = c & 1;
    const exy = edges[x * 2 + y];
    const exz = edges[4 + x * 2 + z];
    const eyz = edges[8 + y * 2 + z];
    const c1 = nbr[6 * (exy < 0 ? none : exy) + 4 + z];
    const c2 = nbr[6 * (exz < 0 ? none : exz) + 2 + y];
    const c3 = nbr[6 * (eyz < 0 ? none : eyz) + x];
    const near = (exy >= 0) + (exz >= 0) + (eyz >= 0) + ((c1 & c2 & c3) >= 0);
    if (near >= 2) outer |= 1 << c;
    if (c === 0) lowerCorner = c1 >= 0 ? c1 : c2 >= 0 ? c2 : c3;
  }
  const mask = lv.mask;
  const m = (at) => mask[at < 0 ? none : at];
  const diagonal = DIAGONAL_FROM[4 * 256 + m(nbr[o])] | DIAGONAL_FROM[2 * 256 + m(nbr[o + 2])] |
    DIAGONAL_FROM[256 + m(nbr[o + 4])] | DIAGONAL_FROM[6 * 256 + m(edges[0])] |
    DIAGONAL_FROM[5 * 256 + m(edges[4])] | DIAGONAL_FROM[3 * 256 + m(edges[8])] | DIAGONAL_FROM[7 * 256 + m(lowerCorner)];
  return outer | (diagonal << 8);
}

function edge(nbr, none, o, d1, d2) {
  const a = nbr[o + d1];
  const b = nbr[o + d2];
  const e = nbr[6 * (a < 0 ? none : a) + d2];
  return e >= 0 ? e : nbr[6 * (b < 0 ? none : b) + d1];
}

// The 8 child bits of cell i, child 0 first; a last bit that must be 1 is implied. `v2`: version
// 2's contexts; `edges`: scratch; `mix`: version 3's and 4's mixer (null before); `planes`: the
// plane memory's state per child (version 4).
function decodeMask(rc, young, age, base, lv, i, v2, edges, mix, planes) {
  const o = 6 * i;
  let exists = 0;
  let facing = 0;
  for (let axis = 0; axis < 3; ++axis) {
    const lo = lv.nbr[o + 2 * axis];
    if (lo >= 0) {
      exists |= 1 << axis;
      facing |= FACING[axis * 256 + lv.mask[lo]];
    }
    if (lv.nbr[o + 2 * axis + 1] >= 0) exists |= 8 << axis;
  }
  const sides = exists * 8;
  const around = v2 ? surroundings(lv, i, edges) : 0;
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
      bit = mix ? mix.bit(rc, young, age, model, c, m, lv.parent[i], near, ones > 0, exists, planes[c]) : rc.youngBit(young, age, model);
    }
    m |= bit << c;
    if (ones < most) ones += bit;
  }
  return m;
}

// The next level's cells: children of the expanded cells, with their face neighbours.
function expand(cur, level, levels, kids, positions) {
  const base = new Int32Array(cur.n).fill(-1);
  let total = 0;
  for (let i = 0; i < cur.n; ++i) {
    if (level >= levels || cur.first[i]) {
      base[i] = total;
      total += POP[cur.mask[i]];
    }
  }
  const next = newLevel(total, positions);
  let j = 0;
  let fresh = 0;
  for (let i = 0; i < cur.n; ++i) {
    if (base[i] < 0) continue;
    const mask = cur.mask[i];
    for (let c = 0, r = 0; c < 8; ++c) {
      if (!((mask >> c) & 1)) continue;
      let id;
      let isFirst;
      if (level + 1 === levels) {
        id = cur.kids[i] + r;
        isFirst = 1;
      } else if (level < levels) {
        id = kids[cur.kids[i] + r];
        isFirst = id === fresh ? 1 : 0;
        if (isFirst) ++fresh;
      } else {
        id = cur.id[i] * 8 + c;
        isFirst = cur.first[i];
      }
      ++r;
      next.id[j] = id;
      next.first[j] = isFirst;
      next.parent[j] = mask;
      if (positions) {
        next.pos[3 * j] = 2 * cur.pos[3 * i] + ((c >> 2) & 1);
        next.pos[3 * j + 1] = 2 * cur.pos[3 * i + 1] + ((c >> 1) & 1);
        next.pos[3 * j + 2] = 2 * cur.pos[3 * i + 2] + (c & 1);
      }
      for (let d = 0; d < 6; ++d) {
        const bit = 4 >> (d >> 1);
        const inside = (d & 1) ? !(c & bit) : (c & bit) !== 0;
        const sib = c ^ bit;
        const owner = inside ? i : cur.nbr[6 * i + d];
        next.nbr[6 * j + d] = owner >= 0 && base[owner] >= 0 && ((cur.mask[owner] >> sib) & 1)
          ? base[owner] + rank(cur.mask[owner], sib)
          : -1;
      }
      ++j;
    }
  }
  return next;
}

// Equal bricks become one, numbered in the order first seen (open addressing on the 64 bits).
function mergeBricks(slotLo, slotHi, bricks) {
  const n = slotLo.length;
  let cap = 16;
  while (cap < 2 * n) cap *= 2;
  const table = new Int32Array(cap).fill(-1);
  const brickLo = new Uint32Array(bricks);
  const brickHi = new Uint32Array(bricks);
  const ids = new Uint32Array(n);
  let count = 0;
  for (let s = 0; s < n; ++s) {
    const lo = slotLo[s];
    const hi = slotHi[s];
    let h = Math.imul(lo ^ Math.imul(hi, 0x9e3779b1), 0x85ebca6b) & (cap - 1);
    for (;;) {
      const k = table[h];
      if (k < 0) {
        if (count === bricks) throw corrupt('geometry stream holds more bricks than its header declares');
        brickLo[count] = lo;
        brickHi[count] = hi;
        table[h] = count;
        ids[s] = count++;
        break;
      }
      if (brickLo[k] === lo && brickHi[k] === hi) {
        ids[s] = k;
        break;
      }
      h = (h + 1) & (cap - 1);
    }
  }
  if (count !== bricks) throw corrupt('geometry stream holds fewer bricks than its header declares');
  return { ids, brickLo, brickHi };
}

export function decodeSpatial(rc, depth, counts, version) {
  const levels = depth - 2;
  const v2 = version >= 2;
  const edges = new Int32Array(12);
  const mix = version >= 3 ? new MaskMixer(version >= 4) : null;
  const planes = version >= 4;
  const last = [null, null, null];
  const states = new Uint8Array(8);
  const young = newModels(CLASSES * MASK_CONTEXTS);
  const age = new Uint8Array(CLASSES * MASK_CONTEXTS);
  const p = newModels(REF_BASE + CLASSES * GAMMA_MODELS);
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
    const n = internal ? counts[level] : 0;
    const levelMasks = new Uint8Array(n);
    const first = new Uint32Array(n + 1);
    const kids = new GrowableU32(internal && level + 1 < levels ? Math.min(8 * n, 2 * counts[level + 1]) : 0);
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
      const mask = decodeMask(rc, young, age, maskBase, cur, i, v2, edges, mix, states);
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
      for (let c = count; c > 0; --c) {
        let k;
        if (seen > 0 && rc.bit(p, flagModel)) {
          k = rc.gamma(p, refBase, bitWidth(seen)) - 1;
          if (k >= seen) throw corrupt('geometry stream refers to a node not yet seen');
        } else {
          k = seen++;
          if (seen > counts[level + 1]) throw corrupt('geometry stream holds more nodes than its header declares');
        }
        kids.push(k);
      }
    }
    if (rc.overrun()) throw corrupt('geometry stream ends early');
    if (level + 1 < levels && seen !== counts[level + 1]) throw corrupt('geometry stream holds fewer nodes than its header declares');
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
  const merged = mergeBricks(slotLo, slotHi, counts[levels]);
  if (levels > 0) children[levels - 1] = merged.ids;
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
