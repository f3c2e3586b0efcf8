#include "pointdag/color/lossless_predict.h"

namespace pointdag::lossless {
namespace {

// Version 2, beyond ±2 for voxels with nothing nearer: max(1, 64 / d²) (d² from 9 to 48).
constexpr Weights kFar = [] {
  Weights w{};
  for (size_t d2 = 9; d2 < w.size(); ++d2) w[d2] = std::max<int>(1, static_cast<int>(64 / d2));
  return w;
}();

// Version 3, the wide weighting reaching ±4: 64 times kWide within ±2, 512 / d² beyond.
constexpr Weights kWideFar = [] {
  Weights w{};
  for (size_t d2 = 1; d2 < w.size(); ++d2) w[d2] = kWide[d2] > 0 ? 64 * kWide[d2] : static_cast<int>(512 / d2);
  return w;
}();

}  // namespace

void CellMeans::Enter(size_t i) {
  for (int l = kFirstLevel; l <= kMaxDepth; ++l) {
    if (i > 0 && morton_[i] >> (3 * l) == morton_[i - 1] >> (3 * l)) break;  // so are the larger ones
    start_[l] = {i, sum_};
  }
}

Prediction CellMeans::Before(size_t i) const {
  Prediction p;
  for (int l = kFirstLevel; l <= kMaxDepth; ++l) {
    const auto& [first, at] = start_[l];
    const int64_t n = static_cast<int64_t>(i - first);
    if (n == 0) continue;
    const auto mean = [n](int64_t sum) { return static_cast<int>((sum + n / 2) / n); };
    p = {mean(sum_[0] - at[0]), mean(sum_[1] - at[1]), mean(sum_[2] - at[2]), 0, 0, 0, true};
    break;
  }
  return p;
}

Prediction Predict(std::span<const Neighbour> found, std::span<const Rgb8> colors, const Weights& weights) {
  Prediction p;
  int w = 0, g = 0, rg = 0, bg = 0;
  for (const Neighbour& n : found) {
    const Rgb8 c = colors[n.index];
    const int wi = weights[n.d2];
    w += wi;
    g += wi * c.g;
    rg += wi * (c.r - c.g);
    bg += wi * (c.b - c.g);
  }
  if (w == 0) return p;
  p = {Div(g, w), Div(rg, w), Div(bg, w), 0, 0, 0, false};
  int sg = 0, srg = 0, sbg = 0;
  for (const Neighbour& n : found) {
    const Rgb8 c = colors[n.index];
    const int wi = weights[n.d2];
    sg += wi * std::abs(c.g - p.g);
    srg += wi * std::abs(c.r - c.g - p.rg);
    sbg += wi * std::abs(c.b - c.g - p.bg);
  }
  p.spread_g = Div(sg, w);
  p.spread_rg = Div(srg, w);
  p.spread_bg = Div(sbg, w);
  return p;
}

Predictor::Predictor(std::span<const uint64_t> morton, int version) : morton_(morton), version_(version) {
  misses_.resize(morton.size());
  Reset();
}

void Predictor::Reset() {
  if (!morton_.empty() && version_ >= 3) cells_.emplace(morton_);
}

Predicted Swapped(const Predicted& p) {
  const auto swap = [](Prediction q) {
    std::swap(q.rg, q.bg);
    std::swap(q.spread_rg, q.spread_bg);
    return q;
  };
  return {swap(p.chosen), swap(p.near), swap(p.wide)};
}

Prediction Predictor::operator()(std::span<const Rgb8> colors, size_t i, const Neighbourhood& around, Predicted* log) {
  const Prediction p = Compute(colors, i, around);
  if (log != nullptr) *log = {p, near_, wide_};
  return p;
}

Prediction Predictor::Replay(size_t i, const Predicted& known) {
  if (cells_) cells_->Enter(i);
  near_ = known.near, wide_ = known.wide;
  return known.chosen;
}

Prediction Predictor::Compute(std::span<const Rgb8> colors, size_t i, const Neighbourhood& around) {
  near_ = wide_ = Prediction{};
  if (!morton_.empty()) {
    if (cells_) cells_->Enter(i);
    if (around.far) {
      const Prediction far = Predict(around.found, colors, kFar);
      if (!far.none) return far;
    } else {
      near_ = Predict(around.adjacent, colors, kNear);
      wide_ = Predict(around.found, colors, around.reach ? kWideFar : kWide);
      int near_miss = 0, wide_miss = 0;
      for (const Neighbour& n : around.adjacent) {
        near_miss += misses_[n.index][0];
        wide_miss += misses_[n.index][1];
      }
      const Prediction& best = near_.none || (!wide_.none && wide_miss <= near_miss) ? wide_ : near_;
      if (!best.none) return best;
      if (cells_) return cells_->Before(i);
    }
  }
  Prediction p;
  if (i > 0) {
    const Rgb8 c = colors[i - 1];
    p = {c.g, c.r - c.g, c.b - c.g, 0, 0, 0, true};  // a weaker guess: its own contexts
  }
  return p;
}

void Predictor::Record(size_t i, const Rgb8& c) {
  if (misses_.empty()) return;
  misses_[i] = {static_cast<uint16_t>(near_.none ? 0 : Miss(near_, c)), static_cast<uint16_t>(wide_.none ? 0 : Miss(wide_, c))};
  if (cells_) cells_->Add(c);
}

}  // namespace pointdag::lossless
