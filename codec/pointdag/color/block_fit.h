// Stage 5a: fitting one block of consecutive colors with two endpoints and per-color weights
// (the BC/ASTC idea of Papers IIA and IIB, applied to the 1D Morton-ordered color array).
//
// A block of n colors with b bits per weight stores endpoints A and B; color i is rebuilt as
// A + (B - A) * w_i / (2^b - 1), rounded per channel. With b = 0 every color is A.
// FitBlock() finds A and B along the colors' principal axis, picks each weight by projection, then
// refines A and B by least squares for those weights (keeping the better of the two fits).
#pragma once

#include <cstddef>
#include <cstdint>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

constexpr int kMaxWeightBits = 4;

struct Endpoints {
  Rgb8 a, b;
};

struct BlockFit {
  Endpoints ends;
  double sse = 0;  // squared error summed over the block's colors and their three channels
};

// `give_up_above`: once the error is known to exceed it, stop and return an error above it (the
// merge encoder only needs to know that a candidate fails its threshold).
BlockFit FitBlock(const Rgb8* colors, size_t n, int bits, double give_up_above = 1e300);

// The weight that rebuilds `c` best from `ends` (projection onto the segment, rounded).
uint32_t ChooseWeight(const Rgb8& c, const Endpoints& ends, int bits);

inline Rgb8 Interpolate(const Endpoints& e, uint32_t w, int bits) {
  if (bits == 0) return e.a;
  const uint32_t m = (1u << bits) - 1;
  const auto mix = [&](uint8_t a, uint8_t b) { return static_cast<uint8_t>((a * (m - w) + b * w + m / 2) / m); };
  return {mix(e.a.r, e.b.r), mix(e.a.g, e.b.g), mix(e.a.b, e.b.b)};
}

inline double SquaredError(const Rgb8& x, const Rgb8& y) {
  const double dr = x.r - y.r, dg = x.g - y.g, db = x.b - y.b;
  return dr * dr + dg * dg + db * db;
}

}  // namespace pointdag
