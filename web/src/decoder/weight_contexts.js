// Spatial contexts of the block color stream's weights (versions 3 and 4, leaf mode), computed as
// codec/pointdag/color/weight_context.cc WeightContexts computes them: the mean of the decoded
// colors of the voxel's face, edge and corner neighbours that precede it in Morton order (weighted
// 4 / 2 / 1 for faces / edges / corners), projected onto the current block's segment A -> B and
// rounded to its weight steps; 16 + the previous weight without such neighbours. Neighbours are
// found by cell in a hash table (the C++ one finds them through 4x4x4 bricks: the same voxels).

// Contexts per weight width (kSpatialWeightContexts).
export const SPATIAL_WEIGHT_CONTEXTS = 33;

// Voxels of a block whose neighbours predict its endpoint A (kPredictingVoxels, version 4).
const PREDICTING_VOXELS = 64;

// Version 4: the cells two away (the 5x5x5 shell) that can precede, where none of the 26 around
// does, weighted by squared distance d² 4 -> 3, 5 or 6 -> 2, 8, 9 or 12 -> 1.
const FAR_OFFSETS = [];
for (let dx = -2; dx <= 2; ++dx) {
  for (let dy = -2; dy <= 2; ++dy) {
    for (let dz = -2; dz <= 2; ++dz) {
      if (Math.max(Math.abs(dx), Math.abs(dy), Math.abs(dz)) < 2 || (dx >= 0 && dy >= 0 && dz >= 0)) continue;
      const d2 = dx * dx + dy * dy + dz * dz;
      FAR_OFFSETS.push(dx, dy, dz, d2 === 4 ? 3 : d2 <= 6 ? 2 : 1);
    }
  }
}

// The neighbour offsets that can precede a voxel in Morton order, with their weights: the code
// grows with each coordinate, so the 7 offsets with no negative component never do.
const OFFSETS = [];
for (let dx = -1; dx <= 1; ++dx) {
  for (let dy = -1; dy <= 1; ++dy) {
    for (let dz = -1; dz <= 1; ++dz) {
      if (dx < 0 || dy < 0 || dz < 0) OFFSETS.push(dx, dy, dz, 8 >> ((dx !== 0) + (dy !== 0) + (dz !== 0)));
    }
  }
}

function hash(x, y, z) {
  return Math.imul(x, 0x9e3779b1) ^ Math.imul(y, 0x85ebca77) ^ Math.imul(z, 0xc2b2ae3d);
}

export class WeightContexts {
  // `coords`: x, y, z per voxel, in Morton order (unique cells).
  constructor(coords) {
    const count = coords.length / 3;
    let capacity = 16;
    while (capacity < 2 * count) capacity *= 2;
    this.coords = coords;
    this.mask = capacity - 1;
    this.slots = new Int32Array(capacity);  // index + 1, 0 = empty
    this.sum = new Int32Array(4);
    for (let i = 0; i < count; ++i) {
      let s = hash(coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]) & this.mask;
      while (this.slots[s] !== 0) s = (s + 1) & this.mask;
      this.slots[s] = i + 1;
    }
  }

  // The index of the voxel at (x, y, z), or -1.
  find(x, y, z) {
    const { coords, slots, mask } = this;
    for (let s = hash(x, y, z) & mask; slots[s] !== 0; s = (s + 1) & mask) {
      const j = slots[s] - 1;
      if (coords[3 * j] === x && coords[3 * j + 1] === y && coords[3 * j + 2] === z) return j;
    }
    return -1;
  }

  // Where color i's preceding neighbours' mean color lies on the segment A -> B of a block with
  // `bits` per weight (Position in weight_context.cc); with `far`, where none of the 26 around
  // precedes, the cells two away. -1 without such neighbours, else (far << 16) | (step << 8) | half
  // step. `decoded` holds the colors before i (RGB per color).
  position(i, decoded, ar, ag, ab, br, bg, bb, bits, far) {
    const x = this.coords[3 * i], y = this.coords[3 * i + 1], z = this.coords[3 * i + 2];
    const sum = this.sum;  // the neighbours' colors, weighted, and their weights
    sum.fill(0);
    this.gather(OFFSETS, i, x, y, z, decoded, sum);
    const beyond = sum[3] === 0 && far;
    if (beyond) this.gather(FAR_OFFSETS, i, x, y, z, decoded, sum);
    const total = sum[3];
    if (total === 0) return -1;
    const flag = beyond ? 1 << 16 : 0;
    const m = (1 << bits) - 1;
    const sr = br - ar, sg = bg - ag, sb = bb - ab;
    const len2 = sr * sr + sg * sg + sb * sb;
    const dot = (sum[0] - total * ar) * sr + (sum[1] - total * ag) * sg + (sum[2] - total * ab) * sb;
    if (dot <= 0 || len2 === 0) return flag;
    const unit = 2 * total * len2;
    return flag | (Math.min(m, Math.floor((2 * dot * m + total * len2) / unit)) << 8) | Math.min(2 * m, Math.floor((4 * dot * m + total * len2) / unit));
  }

  // Adds the decoded colors (weighted) and weights of the cells at `offsets` from (x, y, z) that
  // precede voxel i into sum.
  gather(offsets, i, x, y, z, decoded, sum) {
    for (let k = 0; k < offsets.length; k += 4) {
      const nx = x + offsets[k], ny = y + offsets[k + 1], nz = z + offsets[k + 2];
      if (nx < 0 || ny < 0 || nz < 0) continue;
      const j = this.find(nx, ny, nz);
      if (j < 0 || j >= i) continue;  // absent, or not decoded yet
      const weight = offsets[k + 3];
      sum[0] += weight * decoded[3 * j];
      sum[1] += weight * decoded[3 * j + 1];
      sum[2] += weight * decoded[3 * j + 2];
      sum[3] += weight;
    }
  }

  // Version 3's context of color i's weight: the neighbours' step, else 16 + `prev`.
  of(i, decoded, ar, ag, ab, br, bg, bb, bits, prev) {
    const p = this.position(i, decoded, ar, ag, ab, br, bg, bb, bits, false);
    return p < 0 ? 16 + prev : p >> 8;
  }

  // The block of colors [start, start + length)'s preceding neighbours (Surroundings in
  // weight_context.cc): of its first PREDICTING_VOXELS voxels, the neighbours decoded before
  // `start`, their weighted colors summed into sums[0..2] and their weights into sums[3].
  surroundings(start, length, decoded, sums) {
    sums.fill(0);
    const stop = start + Math.min(length, PREDICTING_VOXELS);
    for (let i = start; i < stop; ++i) {
      const x = this.coords[3 * i], y = this.coords[3 * i + 1], z = this.coords[3 * i + 2];
      for (let k = 0; k < OFFSETS.length; k += 4) {
        const nx = x + OFFSETS[k], ny = y + OFFSETS[k + 1], nz = z + OFFSETS[k + 2];
        if (nx < 0 || ny < 0 || nz < 0) continue;
        const j = this.find(nx, ny, nz);
        if (j < 0 || j >= start) continue;  // absent, or not decoded before the block
        const weight = OFFSETS[k + 3];
        sums[0] += weight * decoded[3 * j];
        sums[1] += weight * decoded[3 * j + 1];
        sums[2] += weight * decoded[3 * j + 2];
        sums[3] += weight;
      }
    }
  }
}
