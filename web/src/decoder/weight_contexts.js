// Spatial contexts of the block color stream's weights (version 3, leaf mode), computed as
// codec/pointdag/color/weight_context.cc WeightContexts::Of computes them: the mean of the decoded
// colors of the voxel's face, edge and corner neighbours that precede it in Morton order (weighted
// 4 / 2 / 1 for faces / edges / corners), projected onto the current block's segment A -> B and
// rounded to its weight steps; 16 + the previous weight without such neighbours. Neighbours are
// found by cell in a hash table (the C++ one finds them through 4x4x4 bricks: the same voxels).

// Contexts per weight width (kSpatialWeightContexts).
export const SPATIAL_WEIGHT_CONTEXTS = 33;

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

  // The context of color i's weight; `decoded` holds the colors before i (RGB per color).
  of(i, decoded, ar, ag, ab, br, bg, bb, bits, prev) {
    const x = this.coords[3 * i], y = this.coords[3 * i + 1], z = this.coords[3 * i + 2];
    let r = 0, g = 0, b = 0, total = 0;  // the neighbours' colors, weighted
    for (let k = 0; k < OFFSETS.length; k += 4) {
      const nx = x + OFFSETS[k], ny = y + OFFSETS[k + 1], nz = z + OFFSETS[k + 2];
      if (nx < 0 || ny < 0 || nz < 0) continue;
      const j = this.find(nx, ny, nz);
      if (j < 0 || j >= i) continue;  // absent, or not decoded yet
      const weight = OFFSETS[k + 3];
      r += weight * decoded[3 * j];
      g += weight * decoded[3 * j + 1];
      b += weight * decoded[3 * j + 2];
      total += weight;
    }
    if (total === 0) return 16 + prev;
    const m = (1 << bits) - 1;
    const sr = br - ar, sg = bg - ag, sb = bb - ab;
    const len2 = sr * sr + sg * sg + sb * sb;
    const dot = (r - total * ar) * sr + (g - total * ag) * sg + (b - total * ab) * sb;
    if (dot <= 0 || len2 === 0) return 0;
    return Math.min(m, Math.floor((2 * dot * m + total * len2) / (2 * total * len2)));
  }
}
