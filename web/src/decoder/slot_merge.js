// Geometry coder 2's slots (codec/pointdag/dag/slot_merge.h, proto/PDAG_FORMAT.md §2.2): the
// bricks, and from stream version 5 the nodes of heights 3 and 4, are coded at every occurrence;
// equal ones become one here, bottom-up, numbered in the order first seen (the canonical order).
import { corrupt } from './pdag_error.js';
import { bitWidth } from './range_coder.js';
import { POP } from './spatial_context.js';

// The first level whose nodes are slots (levels = D − 2 internal levels), as SlotLevel.
export const slotLevel = (levels, version) => (version >= 5 && levels >= 2 ? Math.max(levels - 2, 1) : levels);

// Equal bricks become one, numbered in the order first seen (open addressing on the 64 bits).
// `declared`: the level table's count (null in version 8: as many as there are).
export function mergeBricks(slotLo, slotHi, declared) {
  const n = slotLo.length;
  const bricks = declared ?? n;
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
        if (count === declared) throw corrupt('geometry stream holds more bricks than its header declares');
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
  if (declared !== null && count !== declared) throw corrupt('geometry stream holds fewer bricks than its header declares');
  return { ids, brickLo: brickLo.subarray(0, count), brickHi: brickHi.subarray(0, count) };
}

// Equal nodes of one slot level (the same mask and children) become one: returns the level's
// distinct masks, where their children start and the children, and each slot's number.
// `declared`: as mergeBricks'.
export function mergeLevel(masks, kids, declared) {
  const n = masks.length;
  const most = declared === null ? n : Math.min(declared, n);
  const cap = 2 ** (bitWidth(most) + 1);
  const table = new Int32Array(cap).fill(-1);
  const uniqueMasks = new Uint8Array(declared ?? n);
  const starts = new Uint32Array((declared ?? n) + 1);
  const uniqueKids = new Uint32Array(kids.length);
  const ids = new Uint32Array(n);
  let count = 0;
  let used = 0;
  for (let j = 0, pos = 0; j < n; ++j) {
    const mask = masks[j];
    const end = pos + POP[mask];
    let h = mask;
    for (let k = pos; k < end; ++k) h = Math.imul(h ^ kids[k], 0x01000193);
    h = Math.imul(h ^ (h >>> 15), 0x2c1b3c6d) >>> 0;
    h &= cap - 1;
    for (;;) {
      const u = table[h];
      if (u < 0) {
        if (count === declared) throw corrupt('geometry stream holds more nodes than its header declares');
        uniqueMasks[count] = mask;
        starts[count] = used;
        for (let k = pos; k < end; ++k) uniqueKids[used++] = kids[k];
        table[h] = count;
        ids[j] = count++;
        break;
      }
      if (uniqueMasks[u] === mask && sameKids(uniqueKids, starts[u], kids, pos, end)) {
        ids[j] = u;
        break;
      }
      h = (h + 1) & (cap - 1);
    }
    pos = end;
  }
  if (declared !== null && count !== declared) throw corrupt('geometry stream holds fewer nodes than its header declares');
  starts[count] = used;
  return { masks: uniqueMasks.subarray(0, count), first: starts.subarray(0, count + 1), kids: uniqueKids.slice(0, used), ids };
}

function sameKids(a, at, b, from, end) {
  for (let k = from; k < end; ++k, ++at) if (a[at] !== b[k]) return false;
  return true;
}
