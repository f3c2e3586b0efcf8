// Geometry coder 2's view of a cell's surroundings (proto/PDAG_FORMAT.md §2.2), as
// codec/pointdag/dag/spatial_context.{h,cc} build it, bit for bit: the cells of a level with their
// face links, the context tables, the plane memory, version 5's child-level pattern.

export const POP = Uint8Array.from({ length: 256 }, (_, i) => {
  let n = 0;
  for (let v = i; v; v &= v - 1) ++n;
  return n;
});
const rank = (mask, bit) => POP[mask & ((1 << bit) - 1)];

// Cells 0..n−1 and a sentinel row n (no neighbours, mask 0) that version 2's lookups go through;
// `positions`: x, y, z per cell (version 4's plane memory).
export function newLevel(n, positions) {
  const nbr = new Int32Array(6 * (n + 1));
  nbr.fill(-1, 6 * n);
  return { n, id: new Uint32Array(n), first: new Uint8Array(n), parent: new Uint8Array(n), nbr, mask: new Uint8Array(n + 1), kids: new Uint32Array(n), pos: new Uint32Array(positions ? 3 * n : 0) };
}

// Version 4's plane memory, as spatial_coder.cc's PlaneMemory: per axis and plane of the next level,
// 0 = no cell spanning it coded yet, 1 = the last one had no children there, 2 = it had.
const LOW_HALF = [0x0f, 0x33, 0x55];
export function planeStates(last, pos, i, out) {
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
export function planeRecord(last, pos, i, mask) {
  for (let axis = 0; axis < 3; ++axis) {
    const p = 2 * pos[3 * i + axis];
    last[axis][p] = mask & LOW_HALF[axis] ? 2 : 1;
    last[axis][p + 1] = mask & ~LOW_HALF[axis] & 0xff ? 2 : 1;
  }
}

// The context's parts as tables, as spatial_coder.cc builds them: SIDES[exists * 8 + c] (exists =
// upper << 3 | lower neighbours present), SIBLINGS[c * 256 + m], FACING[axis * 256 + mask] (4 bits a child).
export const SIDES = new Uint8Array(64 * 8);
export const SIBLINGS = new Uint8Array(8 * 256);
export const FACING = new Uint32Array(3 * 256);
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
export const DIAGONAL_SELF = new Uint8Array(8);
for (let c = 0; c < 8; ++c) {
  for (const o of [6, 5, 3, 7]) {
    const p = o & ~c;
    if (p === 0) DIAGONAL_SELF[c] |= 1 << (c ^ o);
    else for (let m = 0; m < 256; ++m) if ((m >> (c ^ o)) & 1) DIAGONAL_FROM[p * 256 + m] |= 1 << c;
  }
}

// Version 5's child-level pattern, as spatial_context.h's kPatternLayout and tables: per child c,
// PATTERN_COUNT[c] neighbour bits (its face and edge neighbours on its level coded before it, in
// offset order), then its 3 neighbours at −2; PATTERN_SELF[c * 256 + mask so far]: the lower
// siblings' bits; per lower cell o = 1..6 (bit 4 >> axis: −1 on that axis), PATTERN_COMPACT[o * 256 +
// mask]: its children on our side, and PATTERN_FROM[(o * 16 + those) * 8 + c]: what they give child c.
export const PATTERN_COUNT = new Int32Array(8);
export const PATTERN_SELF = new Uint16Array(8 * 256);
const PATTERN_COMPACT = new Uint8Array(7 * 256);
const PATTERN_FROM = new Uint16Array(7 * 16 * 8);
{
  const bits = [];  // per c: [o, child] of each neighbour bit
  for (let c = 0; c < 8; ++c) {
    const cc = [(c >> 2) & 1, (c >> 1) & 1, c & 1];
    bits.push([]);
    for (let dx = -1; dx <= 1; ++dx) {
      for (let dy = -1; dy <= 1; ++dy) {
        for (let dz = -1; dz <= 1; ++dz) {
          const d = [dx, dy, dz];
          const moved = (dx !== 0) + (dy !== 0) + (dz !== 0);
          if (moved === 0 || moved === 3) continue;
          let o = 0;
          let child = 0;
          let known = true;
          for (let a = 0; a < 3; ++a) {
            const g = cc[a] + d[a];
            if (g > 1) known = false;
            if (g < 0) o |= 4 >> a;
            child |= (g & 1) << (2 - a);
          }
          if (known && (o !== 0 || child < c)) bits[c].push([o, child]);
        }
      }
    }
    PATTERN_COUNT[c] = bits[c].length;
    bits[c].forEach(([o, child], k) => {
      if (o !== 0) return;
      for (let m = 0; m < 256; ++m) if ((m >> child) & 1) PATTERN_SELF[c * 256 + m] |= 1 << k;
    });
  }
  for (let o = 1; o < 7; ++o) {
    const ours = [0, 1, 2, 3, 4, 5, 6, 7].filter((child) => (child & o) === o);
    for (let m = 0; m < 256; ++m) ours.forEach((child, at) => { PATTERN_COMPACT[o * 256 + m] |= ((m >> child) & 1) << at; });
    for (let index = 0; index < 16; ++index) {
      let m = 0;
      ours.forEach((child, at) => { m |= ((index >> at) & 1) << child; });
      for (let c = 0; c < 8; ++c) {
        bits[c].forEach(([bo, child], k) => {
          if (bo === o && (m >> child) & 1) PATTERN_FROM[(o * 16 + index) * 8 + c] |= 1 << k;
        });
      }
    }
  }
}

// Version 2's view beyond the faces, as spatial_context.h's Surroundings (through the sentinel row
// `none`): returns outer (bits 0..7: at least 2 of octant c's 3 edge and 1 corner neighbours exist)
// | diagonal << 8 (bit c: a lower diagonal neighbour of child c outside the cell is set). With `side`
// (version 5) it also fills side[c] (which of c's 7 neighbours on its side exist: faces x, y, z,
// edges xy, xz, yz, corner) and pattern[c] (the pattern bits the lower cells give child c).
export function surroundings(lv, i, edges, side, pattern) {
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
    const corner = (c1 & c2 & c3) >= 0;
    const near = (exy >= 0) + (exz >= 0) + (eyz >= 0) + corner;
    if (near >= 2) outer |= 1 << c;
    if (c === 0) lowerCorner = c1 >= 0 ? c1 : c2 >= 0 ? c2 : c3;
    if (side) {
      side[c] = (nbr[o + x] >= 0) | ((nbr[o + 2 + y] >= 0) << 1) | ((nbr[o + 4 + z] >= 0) << 2) | ((exy >= 0) << 3) |
        ((exz >= 0) << 4) | ((eyz >= 0) << 5) | (corner << 6);
    }
  }
  const mask = lv.mask;
  const m = (at) => mask[at < 0 ? none : at];
  const diagonal = DIAGONAL_FROM[4 * 256 + m(nbr[o])] | DIAGONAL_FROM[2 * 256 + m(nbr[o + 2])] |
    DIAGONAL_FROM[256 + m(nbr[o + 4])] | DIAGONAL_FROM[6 * 256 + m(edges[0])] |
    DIAGONAL_FROM[5 * 256 + m(edges[4])] | DIAGONAL_FROM[3 * 256 + m(edges[8])] | DIAGONAL_FROM[7 * 256 + m(lowerCorner)];
  if (pattern) {
    // The lower cells at o = 1..6 (−z, −y, −y−z, −x, −x−z, −x−y) give bits only to the children
    // on their side of each of o's axes (c & o = 0).
    const from = PATTERN_FROM;
    const z = (16 + PATTERN_COMPACT[256 + m(nbr[o + 4])]) * 8;
    const y = (32 + PATTERN_COMPACT[512 + m(nbr[o + 2])]) * 8;
    const yz = (48 + PATTERN_COMPACT[768 + m(edges[8])]) * 8;
    const x = (64 + PATTERN_COMPACT[1024 + m(nbr[o])]) * 8;
    const xz = (80 + PATTERN_COMPACT[1280 + m(edges[4])]) * 8;
    const xy = (96 + PATTERN_COMPACT[1536 + m(edges[0])]) * 8;
    pattern[0] = from[z] | from[y] | from[yz] | from[x] | from[xz] | from[xy];
    pattern[1] = from[y + 1] | from[x + 1] | from[xy + 1];
    pattern[2] = from[z + 2] | from[x + 2] | from[xz + 2];
    pattern[3] = from[x + 3];
    pattern[4] = from[z + 4] | from[y + 4] | from[yz + 4];
    pattern[5] = from[y + 5];
    pattern[6] = from[z + 6];
    pattern[7] = 0;
  }
  return outer | (diagonal << 8);
}

function edge(nbr, none, o, d1, d2) {
  const a = nbr[o + d1];
  const b = nbr[o + d2];
  const e = nbr[6 * (a < 0 ? none : a) + d2];
  return e >= 0 ? e : nbr[6 * (b < 0 ? none : b) + d1];
}

// The next level's cells: children of the expanded cells, with their face neighbours.
export function expand(cur, level, levels, kids, positions) {
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
