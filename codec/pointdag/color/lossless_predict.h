// What versions 2 and 3 of the lossless colors' coder share (lossless_context.h, proto/PDAG_FORMAT.md
// §3): a prediction of (G, R-G, B-G) as a weighted mean of decoded neighbours, with how much they
// disagree with it; the share of G's residual that R and B take; the residuals' arithmetic.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <utility>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag::lossless {

struct Prediction {
  int g = 128, rg = 0, bg = 0;                     // G, R-G and B-G
  int spread_g = 0, spread_rg = 0, spread_bg = 0;  // the neighbours' weighted disagreement with them
  bool none = true;                                // nothing to predict from
};

inline int Div(int sum, int weight) { return (sum + weight / 2) / weight; }

// Weights by squared distance (index), up to 3 * 4^2.
using Weights = std::array<int, 49>;
// The near set averages the 26 adjacent voxels, nearer ones weighing more; the wide one averages
// out more noise over the 5x5x5 block.
constexpr Weights kNear = {0, 4, 2, 1};
constexpr Weights kWide = {0, 12, 6, 4, 3, 2, 2, 0, 1, 1, 0, 0, 1};

// The decoded neighbours of a voxel (index and squared distance), folded into predictions.
class Gather {
 public:
  void Clear() { n_ = 0; }
  void Add(size_t j, int d2) {
    if (n_ < items_.size()) items_[n_++] = {j, d2};
  }
  size_t size() const { return n_; }
  std::pair<size_t, int> operator[](size_t k) const { return items_[k]; }
  Prediction Predict(std::span<const Rgb8> colors, const Weights& weights) const {
    Prediction p;
    int w = 0, g = 0, rg = 0, bg = 0;
    for (size_t i = 0; i < n_; ++i) {
      const Rgb8 c = colors[items_[i].first];
      const int wi = weights[items_[i].second];
      w += wi;
      g += wi * c.g;
      rg += wi * (c.r - c.g);
      bg += wi * (c.b - c.g);
    }
    if (w == 0) return p;
    p = {Div(g, w), Div(rg, w), Div(bg, w), 0, 0, 0, false};
    int sg = 0, srg = 0, sbg = 0;
    for (size_t i = 0; i < n_; ++i) {
      const Rgb8 c = colors[items_[i].first];
      const int wi = weights[items_[i].second];
      sg += wi * std::abs(c.g - p.g);
      srg += wi * std::abs(c.r - c.g - p.rg);
      sbg += wi * std::abs(c.b - c.g - p.bg);
    }
    p.spread_g = Div(sg, w);
    p.spread_rg = Div(srg, w);
    p.spread_bg = Div(sbg, w);
    return p;
  }

 private:
  std::array<std::pair<size_t, int>, 9 * 9 * 9 - 1> items_{};  // the ±4 box
  size_t n_ = 0;
};

inline int Miss(const Prediction& p, const Rgb8& c) {
  return std::abs(c.g - p.g) + std::abs(c.r - c.g - p.rg) + std::abs(c.b - c.g - p.bg);
}

// How much of G's residual R (or B) shares: the least-squares slope of its own miss (from the
// neighbours' mean) on G's residual, over a decaying window, in 1/16 (0..1.25).
class Share {
 public:
  int Of(int eg) const {
    const int64_t slope = sxx_ > 0 ? std::clamp<int64_t>(16 * sxy_ / sxx_, 0, 20) : 16;
    return static_cast<int>((slope * eg + (eg >= 0 ? 8 : -8)) / 16);
  }
  void Learn(int eg, int miss) {
    constexpr int k = 4;
    sxy_ += int64_t{eg} * miss - (sxy_ >> k);
    sxx_ += int64_t{eg} * eg - (sxx_ >> k);
  }

 private:
  int64_t sxy_ = 0, sxx_ = 0;
};

inline int Wrap(int v) { return ((v + 128) & 255) - 128; }
inline uint8_t Clamp(int v) { return static_cast<uint8_t>(std::clamp(v, 0, 255)); }
// min(buckets - 1, bit length of v).
inline int Bucket(int v, int buckets) { return std::min(buckets - 1, static_cast<int>(std::bit_width(static_cast<unsigned>(v)))); }

}  // namespace pointdag::lossless
