#include "pointdag/shadow/shadow_ray.h"

#include <algorithm>
#include <limits>

#include "pointdag/shadow/voxel_shadows.h"

namespace pointdag {
namespace {

// Grid units. The slab test's rounding in a 2^21 grid is below 1e-8, so this only ever adds
// candidates, which RayMeetsCell() then rejects.
constexpr double kMargin = 1e-5;
constexpr double kInf = std::numeric_limits<double>::infinity();

std::array<uint32_t, 3> ChildCorner(const std::array<uint32_t, 3>& lo, uint32_t octant, uint32_t half) {
  return {lo[0] + ((octant >> 2) & 1u) * half, lo[1] + ((octant >> 1) & 1u) * half, lo[2] + (octant & 1u) * half};
}

}  // namespace

ShadowRayCaster::ShadowRayCaster(const Svdag& dag, const std::array<double, 3>& travel)
    : dag_(dag), travel_(travel) {
  for (int a = 0; a < 3; ++a) {
    flat_[a] = travel[a] == 0;
    inv_[a] = flat_[a] ? 0 : -1 / travel[a];
    if (travel[a] > 0) flip_ |= 1u << (2 - a);  // the ray runs towards lower coordinates
  }
  stack_.reserve(static_cast<size_t>(8 * (dag.depth + 1)));
}

bool ShadowRayCaster::ChildSlabs::Reach(uint32_t octant) const {
  const uint32_t bx = (octant >> 2) & 1u, by = (octant >> 1) & 1u, bz = octant & 1u;
  const double t0 = std::max(std::max(enter[0][bx], enter[1][by]), std::max(enter[2][bz], 0.0));
  const double t1 = std::min(std::min(exit[0][bx], exit[1][by]), exit[2][bz]);
  return t0 <= t1;
}

void ShadowRayCaster::Slabs(const std::array<uint32_t, 3>& lo, uint32_t half, ChildSlabs& slabs) const {
  for (int a = 0; a < 3; ++a) {
    const double low = static_cast<double>(lo[a]) - origin_[a];
    const double planes[4] = {low - kMargin, low + half - kMargin, low + half + kMargin, low + 2.0 * half + kMargin};
    for (int b = 0; b < 2; ++b) {
      const double near = planes[b], far = planes[b + 2];  // child b spans [near, far] on this axis
      if (flat_[a]) {
        const bool inside = near <= 0 && far >= 0;
        slabs.enter[a][b] = inside ? -kInf : kInf;
        slabs.exit[a][b] = inside ? kInf : -kInf;
      } else {
        const double ta = near * inv_[a], tb = far * inv_[a];
        slabs.enter[a][b] = std::min(ta, tb);
        slabs.exit[a][b] = std::max(ta, tb);
      }
    }
  }
}

bool ShadowRayCaster::BrickBlocks(uint64_t brick, const std::array<uint32_t, 3>& lo) const {
  ChildSlabs cells, voxels;
  Slabs(lo, 2, cells);
  for (uint32_t i = 0; i < 8; ++i) {
    const uint32_t c = i ^ flip_;
    const uint32_t cell = static_cast<uint32_t>(brick >> (8 * c)) & 0xFFu;
    if (!cell || !cells.Reach(c)) continue;
    const auto cell_lo = ChildCorner(lo, c, 2);
    Slabs(cell_lo, 1, voxels);
    for (uint32_t j = 0; j < 8; ++j) {
      const uint32_t v = j ^ flip_;
      if (!((cell >> v) & 1u) || !voxels.Reach(v)) continue;
      const auto voxel = ChildCorner(cell_lo, v, 1);
      if (voxel != self_ && RayMeetsCell(origin_, travel_, voxel)) return true;
    }
  }
  return false;
}

bool ShadowRayCaster::Blocked(const std::array<uint32_t, 3>& voxel) {
  if (dag_.leaves.empty()) return false;
  self_ = voxel;
  for (int a = 0; a < 3; ++a) origin_[a] = voxel[a] + 0.5;
  const int brick_level = dag_.depth - 2;
  stack_.clear();
  stack_.push_back({0, 0, {0, 0, 0}});
  ChildSlabs slabs;
  while (!stack_.empty()) {
    const Entry e = stack_.back();
    stack_.pop_back();
    if (e.level == brick_level) {
      if (BrickBlocks(dag_.leaves[e.ref], e.lo)) return true;
      continue;
    }
    const uint32_t half = uint32_t{1} << (dag_.depth - e.level - 1);
    const uint32_t mask = dag_.Mask(e.ref);
    Slabs(e.lo, half, slabs);
    // Pushed farthest first so that the nearest child is taken next.
    for (int i = 7; i >= 0; --i) {
      const uint32_t octant = static_cast<uint32_t>(i) ^ flip_;
      if (!((mask >> octant) & 1u) || !slabs.Reach(octant)) continue;
      const uint32_t rank = static_cast<uint32_t>(__builtin_popcount(mask & ((1u << octant) - 1)));
      stack_.push_back({dag_.nodes[e.ref + 1 + rank], e.level + 1, ChildCorner(e.lo, octant, half)});
    }
  }
  return false;
}

}  // namespace pointdag
