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

// The mixers' bias input, and one learning step for all of a row's weights (w[wi..], in the order of
// the inputs given; a sixth input only for six-weight rows): w += input x err / 2^11, clamped to
// ±2^22, as the C++ mixers do.
export const MIXER_BIAS = 256;
const MAX_WEIGHT = 1 << 22;
const clampWeight = (v) => (v < -MAX_WEIGHT ? -MAX_WEIGHT : v > MAX_WEIGHT ? MAX_WEIGHT : v);

export function trainMixer(w, wi, err, s0, s1, s2, s3, s4, s5) {
  w[wi] = clampWeight(w[wi] + ((s0 * err) >> 11));
  w[wi + 1] = clampWeight(w[wi + 1] + ((s1 * err) >> 11));
  w[wi + 2] = clampWeight(w[wi + 2] + ((s2 * err) >> 11));
  w[wi + 3] = clampWeight(w[wi + 3] + ((s3 * err) >> 11));
  w[wi + 4] = clampWeight(w[wi + 4] + ((s4 * err) >> 11));
  if (s5 !== undefined) w[wi + 5] = clampWeight(w[wi + 5] + ((s5 * err) >> 11));
}
