// What versions 2 and 3 of the lossless colors' coder share (lossless_context.h, proto/PDAG_FORMAT.md
// §3): the prediction of (G, R-G, B-G) from decoded neighbours, with how much they disagree with it;
// the share of G's residual that R and B take; the residuals' arithmetic.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "pointdag/voxelize/morton.h"
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

// A decoded voxel near the one predicted: its index and squared distance (or, for a column's, the
// squared distance it weighs as).
struct Neighbour {
  uint32_t index;
  uint32_t d2;
};

// The decoded voxels that predict a voxel (lossless_neighbourhood.h finds them): they depend on the
// voxels alone, not on their colors.
struct Neighbourhood {
  std::span<const Neighbour> found;
  std::span<const Neighbour> adjacent;  // those of `found` with d2 <= 3, the only ones kNear weighs
  bool reach = false;  // version 3: fewer than kFewNeighbours within ±2, so those within ±4 joined
  bool far = false;    // version 2: none within ±2; `found` holds those within ±4, to predict alone
};

// The neighbours' colors folded into a prediction, each weighing weights[d2].
Prediction Predict(std::span<const Neighbour> found, std::span<const Rgb8> colors, const Weights& weights);

// A voxel's prediction and the two weightings tried for it. Swapped: the same for the colors with
// R and B swapped (the channel order with the same lead, lossless_transform.h), which the encoder's
// layout trials replay instead of predicting again (the misses that choose the weighting add the
// channels' alike, so the choice is the same).
struct Predicted {
  Prediction chosen, near, wide;
};
Predicted Swapped(const Predicted& p);

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

// The mean (G, R-G, B-G) of the decoded voxels in the smallest cell of 8^3 voxels or more (Morton
// code >> 3L, L >= 3) around voxel i that holds any (version 3): a voxel with no neighbour within
// ±4 is better predicted by it than by the previous color (tiny at 8 ft: 97 % of its voxels, colors
// -2.2 %; larger cells first measured worse everywhere else).
class CellMeans {
 public:
  explicit CellMeans(std::span<const uint64_t> morton) : morton_(morton) {}
  // Voxel i's turn: the cells that begin with it start counting.
  void Enter(size_t i);
  void Add(const Rgb8& c) { sum_ = {sum_[0] + c.g, sum_[1] + c.r - c.g, sum_[2] + c.b - c.g}; }
  // Before voxel i; none when nothing is decoded.
  Prediction Before(size_t i) const;

 private:
  static constexpr int kFirstLevel = 3;
  std::span<const uint64_t> morton_;
  std::array<int64_t, 3> sum_{};  // of colors 0..i-1
  std::array<std::pair<size_t, std::array<int64_t, 3>>, kMaxDepth + 1> start_{};  // per level: first voxel, sum_ there
};

// The prediction of color i from colors [0, i), which both sides know. With the voxels' Morton
// codes: the near and wide weightings of the decoded neighbours within ±2 are tried on every voxel
// and the one that missed less on the adjacent decoded voxels predicts. Version 2 looks within ±4
// (weights kFar) only for a voxel with none within ±2, and falls back on the previous color;
// version 3 adds those within ±4 for a voxel with fewer than 4 (weights kWideFar), and falls back
// on CellMeans. Version 4 may add, by the stream's choice, the last decoded voxels of the columns
// around the voxel, at any height (CausalColumns). Without Morton codes (mipmap colors): the
// previous color.
class Predictor {
 public:
  // `morton`: empty, or one code per color, which must outlive this.
  Predictor(std::span<const uint64_t> morton, int version);
  // Back to the first color, for another stream over the same voxels.
  void Reset();
  // `around`: voxel i's neighbourhood (empty without Morton codes). `log`: where to keep it too.
  Prediction operator()(std::span<const Rgb8> colors, size_t i, const Neighbourhood& around, Predicted* log = nullptr);
  // Voxel i's prediction as `known` (by another trial, for these colors).
  Prediction Replay(size_t i, const Predicted& known);
  // After color i is known: how far each weighting was from it.
  void Record(size_t i, const Rgb8& c);

 private:
  std::span<const uint64_t> morton_;
  int version_;
  std::optional<CellMeans> cells_;
  Prediction Compute(std::span<const Rgb8> colors, size_t i, const Neighbourhood& around);

  std::vector<std::array<uint16_t, 2>> misses_;  // written for each voxel before its neighbours read it
  Prediction near_, wide_;
};

inline int Wrap(int v) { return ((v + 128) & 255) - 128; }
inline uint8_t Clamp(int v) { return static_cast<uint8_t>(std::clamp(v, 0, 255)); }
// min(buckets - 1, bit length of v).
inline int Bucket(int v, int buckets) { return std::min(buckets - 1, static_cast<int>(std::bit_width(static_cast<unsigned>(v)))); }

}  // namespace pointdag::lossless
