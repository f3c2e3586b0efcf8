#include "pointdag/color/lossless_predict.h"

namespace pointdag::lossless {
namespace {

constexpr int kRadius = 2, kFarRadius = 4;
// Version 3: with fewer decoded neighbours than this within ±2, those within ±4 join them (IGN
// 0.1 m: half its voxels have none within ±2).
constexpr int kFewNeighbours = 4;
// Column mode: the columns within ±2 in x and y, and within ±6 for a voxel with fewer than
// kFewNeighbours found by then (IGN 0.1 m, colors: 113,498 bytes with ±2 alone, 112,125 with ±6
// after, 112,633 with ±8).
constexpr int kColumnRadius = 2, kFarColumnRadius = 6;

// A column's voxel weighs as a box voxel at d² = dx² + dy² + 2 (its own column's as a face
// neighbour, d² = 1): its height is unknown to the weights, and a box voxel the same distance off
// in x and y is nearer. Up to kWideFar's last entry.
int ColumnD2(int dxy2) { return dxy2 == 0 ? 1 : std::min(48, dxy2 + 2); }

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

Predictor::Predictor(std::span<const uint64_t> morton, int version, bool columns) : version_(version) {
  if (!morton.empty()) {
    neighbours_.emplace(morton);
    if (version_ >= 3) cells_.emplace(morton);
    if (columns) columns_.emplace(morton);
    misses_.resize(morton.size());
  }
}

Prediction Predictor::operator()(std::span<const Rgb8> colors, size_t i) {
  Gather& gather = gather_;  // a member: its array is not cleared per voxel
  gather.Clear();
  near_ = wide_ = Prediction{};
  if (neighbours_) {
    if (cells_) cells_->Enter(i);
    const auto add = [&gather](size_t j, int d2) { gather.Add(j, d2); };
    neighbours_->ForEach(i, 0, kRadius, add);
    const bool reach = version_ >= 3 && gather.size() < kFewNeighbours;
    if (reach) neighbours_->ForEach(i, kRadius, kFarRadius, add);
    if (columns_) {
      const auto add_column = [&gather](size_t j, int dxy2) { gather.Add(j, ColumnD2(dxy2)); };
      const int box = reach ? kFarRadius : kRadius;
      columns_->ForEach(i, -1, kColumnRadius, box, add_column);
      if (gather.size() < kFewNeighbours) columns_->ForEach(i, kColumnRadius, kFarColumnRadius, box, add_column);
    }
    near_ = gather.Predict(colors, kNear);
    wide_ = gather.Predict(colors, reach ? kWideFar : kWide);
    int near_miss = 0, wide_miss = 0;
    for (size_t k = 0; k < gather.size(); ++k) {
      if (gather[k].second > 3) continue;
      near_miss += misses_[gather[k].first][0];
      wide_miss += misses_[gather[k].first][1];
    }
    const Prediction& best = near_.none || (!wide_.none && wide_miss <= near_miss) ? wide_ : near_;
    if (!best.none) return best;
    if (cells_) return cells_->Before(i);
    neighbours_->ForEach(i, kRadius, kFarRadius, add);
    const Prediction far = gather.Predict(colors, kFar);
    if (!far.none) return far;
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
  if (columns_) columns_->Record(i);
}

}  // namespace pointdag::lossless
