// Logistic mixing's arithmetic, in integers so that every decoder (the JavaScript one included)
// computes the same bits: probabilities in 1/4096, their logits ("stretch") in 1/256 nats. Used by
// the geometry's mask mixer (dag/mask_mixer.h) and the lossless colors (color/lossless_mixing.cc).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

namespace pointdag {

// P(bit = 1) in 1/4096 at d = −2048, −1920, .., 2048 (1/256 nats): 4096 / (1 + e^(−d/256)), rounded.
constexpr std::array<int32_t, 33> kSquashKnots = {1,    2,    4,    6,    10,   17,   27,   45,   74,   120,  194,
                                                  311,  488,  747,  1102, 1546, 2048, 2550, 2994, 3349, 3608, 3785,
                                                  3902, 3976, 4022, 4051, 4069, 4079, 4086, 4090, 4092, 4094, 4095};

// The logistic function, interpolated between the knots: d in 1/256 nats -> P(1) in 1/4096.
constexpr int32_t Squash(int32_t d) {
  const int32_t x = std::clamp(d, -2047, 2047) + 2048;
  const int32_t i = x >> 7, w = x & 127;
  return (kSquashKnots[i] * (128 - w) + kSquashKnots[i + 1] * w + 64) >> 7;
}

// Its inverse on 0..4095: the least d whose Squash reaches p (2047 beyond).
constexpr auto kStretch = [] {
  std::array<int16_t, 4096> t{};
  int32_t next = 0;
  for (int32_t d = -2047; d <= 2047; ++d) {
    for (const int32_t v = Squash(d); next <= v && next < 4096; ++next) t[next] = static_cast<int16_t>(d);
  }
  for (; next < 4096; ++next) t[next] = 2047;
  return t;
}();

// Squash on every d of −2047..2047 (index d + 2047), clamped to 1..4095: the mixer's per-bit lookup.
constexpr auto kSquashTable = [] {
  std::array<int16_t, 4095> t{};
  for (int32_t d = -2047; d <= 2047; ++d) t[d + 2047] = static_cast<int16_t>(std::clamp(Squash(d), 1, 4095));
  return t;
}();

// A probability given outright (the mixer's), for the range coder's Encode/Decode.
struct FixedP0 {
  uint32_t p0;
  uint32_t P0() const { return p0; }
  void Update(int) {}
};

}  // namespace pointdag
