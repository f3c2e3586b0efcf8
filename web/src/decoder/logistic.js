// Integer logistic mixing as codec/pointdag/entropy/logistic.h defines it, bit for bit: shared by
// the geometry's mask mixers (mask_mixer.js, mask_mixer5.js) and the block colors'
// weight mixer (weight_mixer.js).

// P(bit = 1) in 1/4096 at d = −2048, −1920, .., 2048 (1/256 nats).
const KNOTS = Int32Array.from([1, 2, 4, 6, 10, 17, 27, 45, 74, 120, 194, 311, 488, 747, 1102, 1546, 2048, 2550, 2994,
  3349, 3608, 3785, 3902, 3976, 4022, 4051, 4069, 4079, 4086, 4090, 4092, 4094, 4095]);

export function squash(d) {
  const x = (d < -2047 ? -2047 : d > 2047 ? 2047 : d) + 2048;
  const i = x >> 7;
  const w = x & 127;
  return (KNOTS[i] * (128 - w) + KNOTS[i + 1] * w + 64) >> 7;
}

// Its inverse on 0..4095: the least d whose squash reaches p (2047 beyond).
export const STRETCH = new Int16Array(4096);
{
  let next = 0;
  for (let d = -2047; d <= 2047; ++d) {
    for (const v = squash(d); next <= v && next < 4096; ++next) STRETCH[next] = d;
  }
  for (; next < 4096; ++next) STRETCH[next] = 2047;
}


// squash on every d of −2047..2047 (index d + 2047), clamped to 1..4095: the mixer's per-bit lookup.
export const SQUASH_TABLE = new Int16Array(4095);
for (let d = -2047; d <= 2047; ++d) SQUASH_TABLE[d + 2047] = Math.min(Math.max(squash(d), 1), 4095);

// A mixer's d from its dot product of 16.16 weights and stretched inputs (below 2^37 in magnitude:
// exact in doubles), floored and clamped as the C++ shift and std::clamp do.
export function mixerDomain(dot) {
  const d = Math.floor(dot / 65536);
  return d < -2047 ? -2047 : d > 2047 ? 2047 : d;
}
