// Geometry coder 2 (proto/PDAG_FORMAT.md §2.2), read as codec/pointdag/dag/spatial_coder.cc reads
// it, bit for bit: the octree walked level by level in Morton order over the cells the decoder can
// know, each child bit modelled by its known neighbours on its level and its parent's neighbours;
// bricks coded in full at every slot and merged here. Returns readSymbols' shape (dag_stream.js).
import { corrupt } from './pdag_error.js';
import { GrowableU32 } from './growable_u32.js';
import { GAMMA_MODELS, bitWidth, newModels } from './range_coder.js';

const CLASSES = 22;  // heights 0..21
const MASK_CONTEXTS = 4 * 8 * 27;
const FLAG_BASE = 0;
const REF_BASE = CLASSES;
const POP = Uint8Array.from({ length: 256 }, (_, i) => {
  let n = 0;
  for (let v = i; v; v &= v - 1) ++n;
  return n;
});
const rank = (mask, bit) => POP[mask & ((1 << bit) - 1)];

function newLevel(n) {
  return { n, id: new Uint32Array(n), first: new Uint8Array(n), nbr: new Int32Array(6 * n), mask: new Uint8Array(n), kids: new Uint32Array(n) };
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

// The 8 child bits of cell i, child 0 first; a last bit that must be 1 is implied.
function decodeMask(rc, young, age, base, lv, i) {
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
  let m = 0;
  let ones = 0;
  for (let c = 0; c < 8; ++c) {
    let bit = 1;
    if (c < 7 || m !== 0) {
      const lower = ((facing >>> (4 * c)) & 7) | SIBLINGS[c * 256 + m];
      bit = rc.youngBit(young, age, base + (ones * 8 + lower) * 27 + SIDES[sides + c]);
    }
    m |= bit << c;
    if (ones < 3) ones += bit;
  }
  return m;
}

// The next level's cells: children of the expanded cells, with their face neighbours.
function expand(cur, level, levels, kids) {
  const base = new Int32Array(cur.n).fill(-1);
  let total = 0;
  for (let i = 0; i < cur.n; ++i) {
    if (level >= levels || cur.first[i]) {
      base[i] = total;
      total += POP[cur.mask[i]];
    }
  }
  const next = newLevel(total);
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

export function decodeSpatial(rc, depth, counts) {
  const levels = depth - 2;
  const young = newModels(CLASSES * MASK_CONTEXTS);
  const age = new Uint8Array(CLASSES * MASK_CONTEXTS);
  const p = newModels(REF_BASE + CLASSES * GAMMA_MODELS);
  const masks = [];
  const firstChild = [];
  const children = [];
  let slotLo = new Uint32Array(levels === 0 ? 1 : 0);
  let slotHi = new Uint32Array(levels === 0 ? 1 : 0);
  let cur = newLevel(1);
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
    let coded = 0;
    let seen = 0;
    let slots = 0;
    for (let i = 0; i < cur.n; ++i) {
      const id = cur.id[i];
      if (!cur.first[i]) {
        cur.mask[i] = internal ? levelMasks[id] : level > levels ? cellByte(slotLo, slotHi, id) : cellMask(slotLo[id], slotHi[id]);
        continue;
      }
      const mask = decodeMask(rc, young, age, maskBase, cur, i);
      cur.mask[i] = mask;
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
    if (level + 1 < depth) cur = expand(cur, level, levels, kids.a);
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
