#include "pointdag/color/lossless_neighbourhood.h"

namespace pointdag::lossless {
namespace {

constexpr int kRadius = 2, kFarRadius = 4;
// Version 3: with fewer decoded neighbours than this within ±2, those within ±4 join them (IGN
// 0.1 m: half its voxels have none within ±2).
constexpr size_t kFewNeighbours = 4;
// Column mode: the columns within ±2 in x and y, and within ±6 for a voxel with fewer than
// kFewNeighbours found by then (IGN 0.1 m, colors: 113,498 bytes with ±2 alone, 112,125 with ±6
// after, 112,633 with ±8).
constexpr int kColumnRadius = 2, kFarColumnRadius = 6;

// A column's voxel weighs as a box voxel at d² = dx² + dy² + 2 (its own column's as a face
// neighbour, d² = 1): its height is unknown to the weights, and a box voxel the same distance off
// in x and y is nearer. Up to kWideFar's last entry.
int ColumnD2(int dxy2) { return dxy2 == 0 ? 1 : std::min(48, dxy2 + 2); }

}  // namespace

NeighbourhoodSearch::NeighbourhoodSearch(std::span<const uint64_t> morton, int version, bool columns)
    : version_(version), neighbours_(morton) {
  if (columns) columns_.emplace(morton);
}

Neighbourhood NeighbourhoodSearch::Next(size_t i, BoxCounts* box) {
  n_ = adjacent_n_ = 0;
  const auto add = [this](size_t j, int d2) { Add(j, d2); };
  neighbours_.ForEach(i, 0, kRadius, add);
  Neighbourhood around;
  if (n_ == 0 && version_ == 2) {
    neighbours_.ForEach(i, kRadius, kFarRadius, add);
    around.far = true;
  }
  around.reach = version_ >= 3 && n_ < kFewNeighbours;
  if (around.reach) neighbours_.ForEach(i, kRadius, kFarRadius, add);
  if (box != nullptr) *box = {n_, adjacent_n_};
  if (columns_) {
    const auto add_column = [this](size_t j, int dxy2) { Add(j, ColumnD2(dxy2)); };
    const int reached = around.reach ? kFarRadius : kRadius;
    columns_->ForEach(i, -1, kColumnRadius, reached, add_column);
    if (n_ < kFewNeighbours) columns_->ForEach(i, kColumnRadius, kFarColumnRadius, reached, add_column);
    columns_->Record(i);
  }
  around.found = {found_.data(), n_};
  around.adjacent = {adjacent_.data(), adjacent_n_};
  return around;
}

RecordedNeighbourhoods::RecordedNeighbourhoods(NeighbourhoodSearch& search, size_t count) {
  voxels_.reserve(count);
  found_.reserve(count * 8);
  adjacent_.reserve(count * 4);
  for (size_t i = 0; i < count; ++i) {
    NeighbourhoodSearch::BoxCounts box;
    const Neighbourhood around = search.Next(i, &box);
    const size_t begin = found_.size(), adjacent_begin = adjacent_.size();
    found_.insert(found_.end(), around.found.begin(), around.found.end());
    adjacent_.insert(adjacent_.end(), around.adjacent.begin(), around.adjacent.end());
    voxels_.push_back({begin, begin + box.found, found_.size(), adjacent_begin, adjacent_begin + box.adjacent, adjacent_.size(), around.reach});
  }
}

}  // namespace pointdag::lossless
