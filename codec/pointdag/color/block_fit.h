// Stage 5a: fitting one block of consecutive colors with two endpoints and per-color weights
// (the BC/ASTC idea of Papers IIA and IIB, applied to the 1D Morton-ordered color array).
//
// A block of n colors with b bits per weight stores endpoints A and B; color i is rebuilt as
// A + (B - A) * w_i / (2^b - 1), rounded per channel. With b = 0 every color is A.
// BlockFitter::Fit() finds A and B along the colors' principal axis (two power-iteration steps), picks
// each weight by projection, then refines A and B by least squares for those weights (keeping the
// better fit).
//
// Every step is integer arithmetic with a fixed order of operations, so that the Vulkan port
// (gpu/shaders/block_common.glsl) can reproduce it bit for bit: keep the two in step.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

constexpr int kMaxWeightBits = 4;

struct Endpoints {
  Rgb8 a, b;
  friend bool operator==(const Endpoints&, const Endpoints&) = default;
};

constexpr uint64_t kUnknownChroma = UINT64_MAX;

struct BlockFit {
  Endpoints ends;
  uint64_t sse = 0;  // BlockError summed over the block's colors
  // BlockFitter::ChromaError of `ends` where the fit had it from the sums for a few more products
  // (every color rebuilt as A: a leaf, 0 bits, colors all alike), else kUnknownChroma: the
  // variable-rate tree tries hundreds of thousands of 0-bit merges, each also judged by it.
  uint64_t chroma = kUnknownChroma;
};

// Fits blocks inside one run of colors (a macro block). Prefix sums of the colors and of their
// products make a range's mean, covariance and constant-color error O(1), so 0-bit fits never
// touch the colors and wider fits only walk them to place endpoints and weights.
class BlockFitter {
 public:
  explicit BlockFitter(std::span<const Rgb8> colors);

  // Colors [begin, begin + length) with `bits` per weight. `give_up_above`: a fit whose error is
  // known to exceed it may stop early and report any error above it (the merge encoder only needs
  // to know that a candidate fails its threshold); so does one whose first, unrefined error passes
  // twice it, refinement untried (a heuristic: results depend on it, and the Vulkan port does alike).
  BlockFit Fit(uint32_t begin, uint32_t length, int bits, uint64_t give_up_above = UINT64_MAX) const;

  // The chroma part the variable-rate tree adds to a block's error (block_codec.cc): the sum over colors
  // [begin, begin + length) of d^T kChromaWeights d, d = c - Interpolate(ends, ChooseWeight(c, ends, bits),
  // bits). From the sums alone where every color is rebuilt as A (0 bits, or A = B). Every term is
  // >= 0 (kChromaWeights is positive semidefinite), so a walk may stop once its sum passes
  // `give_up_above`, reporting that sum (the merge passes only need to know that a candidate fails).
  uint64_t ChromaError(uint32_t begin, uint32_t length, int bits, const Endpoints& ends,
                       uint64_t give_up_above = UINT64_MAX) const;

 private:
  struct Sums {
    int64_t s[3];   // sum of r, g, b
    int64_t ss[6];  // sum of rr, gg, bb, rg, rb, gb
  };
  Sums RangeSums(uint32_t begin, uint32_t end) const;
  // Whether the per-color loops take their AVX2 copies: the CPU has AVX2 and POINTDAG_NO_AVX2 is unset
  // (that forces the scalar loops, for tests and timings: both give the same integers).
  static bool UseAvx2();

  std::span<const Rgb8> colors_;
  std::vector<std::array<uint32_t, 9>> prefix_;  // prefix_[i]: sums over colors [0, i)
  // Per color, padded with zeros so that the AVX2 loops may read whole chunks past the end:
  std::vector<uint32_t> norms_;                 // c^T Q c (BlockError against black)
  std::vector<uint32_t> chroma_norms_;          // c^T C c, C = kChromaWeights (modulo 2^32: C has negative entries)
  bool avx2_;
  std::array<std::vector<int32_t>, 3> planes_;  // r, g, b; empty without AVX2
};

inline Rgb8 Interpolate(const Endpoints& e, uint32_t w, int bits) {
  if (bits == 0) return e.a;
  const uint32_t m = (1u << bits) - 1;
  const auto mix = [&](uint8_t a, uint8_t b) { return static_cast<uint8_t>((a * (m - w) + b * w + m / 2) / m); };
  return {mix(e.a.r, e.b.r), mix(e.a.g, e.b.g), mix(e.a.b, e.b.b)};
}

inline uint32_t SquaredError(const Rgb8& x, const Rgb8& y) {
  const int32_t dr = x.r - y.r, dg = x.g - y.g, db = x.b - y.b;
  return static_cast<uint32_t>(dr * dr + dg * dg + db * db);
}

// The error blocks are judged by, in 1/1024ths: d^T Q d for the RGB difference d, with Q = 1024 (3 y y^T
// + w (cb cb^T + cr cr^T)) rounded, y, cb, cr the BT.709 luma and chroma rows. Quality is judged on
// PSNR-Y, so luma counts 3/w times more than chroma (w = 1/2: MPEG's 6:1:1); a gray difference costs what
// the RGB squared error does. Q is positive definite, so every term sum below is >= 0.
constexpr int32_t kErrorWeights[3][3] = {{274, 373, 6}, {373, 1753, 71}, {6, 71, 145}};
// The chroma part alone, 1024 x 1/2 (cb cb^T + cr cr^T) rounded (BlockFitter::ChromaError).
constexpr int32_t kChromaWeights[3][3] = {{135, -94, -41}, {-94, 182, -88}, {-41, -88, 129}};

inline uint32_t BlockError(const Rgb8& x, const Rgb8& y) {
  const int32_t d[3] = {x.r - y.r, x.g - y.g, x.b - y.b};
  int32_t e = 0;
  for (int j = 0; j < 3; ++j) e += d[j] * (kErrorWeights[j][0] * d[0] + kErrorWeights[j][1] * d[1] + kErrorWeights[j][2] * d[2]);
  return static_cast<uint32_t>(e);
}

// Q d for the difference d = B - A of two endpoints (each component below 2^20 in magnitude).
inline std::array<int32_t, 3> WeightedAxis(const Endpoints& ends) {
  const int32_t d[3] = {ends.b.r - ends.a.r, ends.b.g - ends.a.g, ends.b.b - ends.a.b};
  std::array<int32_t, 3> q{};
  for (int j = 0; j < 3; ++j) q[j] = kErrorWeights[j][0] * d[0] + kErrorWeights[j][1] * d[1] + kErrorWeights[j][2] * d[2];
  return q;
}

// The weight that rebuilds `c` best from `ends` in BlockError's metric: projection onto the segment
// with the inner product x^T Q y, rounded half up. Both products stay below 2^29.
inline uint32_t ChooseWeight(const Rgb8& c, const Endpoints& ends, int bits) {
  if (bits == 0) return 0;
  const int64_t m = (1 << bits) - 1;
  const std::array<int32_t, 3> q = WeightedAxis(ends);
  const int64_t len2 = (ends.b.r - ends.a.r) * q[0] + (ends.b.g - ends.a.g) * q[1] + (ends.b.b - ends.a.b) * q[2];
  const int64_t dot = (c.r - ends.a.r) * q[0] + (c.g - ends.a.g) * q[1] + (c.b - ends.a.b) * q[2];
  if (dot <= 0) return 0;
  if (dot >= len2) return static_cast<uint32_t>(m);
  return static_cast<uint32_t>((2 * m * dot + len2) / (2 * len2));
}

}  // namespace pointdag
