#include "pointdag/shadow/shadow_ray.h"

#include <algorithm>
#include <limits>

#include "pointdag/shadow/voxel_shadows.h"

namespace pointdag {
namespace {

// Grid units. The slab test's rounding in a 2^21 grid is below 1e-8, so this only ever adds
// candidates, which RayMeetsCell() then rejects.
constexpr double kMargin = 1e-5;

std::array<uint32_t, 3> ChildCorner(const std::array<uint32_t, 3>& lo, uint32_t octant, uint32_t half) {
  return {lo[0] + ((octant >> 2) & 1u) * half, lo[1] + ((octant >> 1) & 1u) * half, lo[2] + (octant & 1u) * half};
}

}  // namespace

ShadowRayCaster::ShadowRayCaster(const Svdag& dag, const std::array<double, 3>& travel)
    : dag_(dag), travel_(travel) {
  for (int a = 0; a < 3; ++a) {
    flat_[a] = travel[a] == 0;
    inv_[a] = flat_[a] ? 0 : -1 / travel[a];
  }
  stack_.reserve(static_cast<size_t>(8 * (dag.depth + 1)));
}

bool ShadowRayCaster::Enters(const std::array<uint32_t, 3>& lo, uint32_t size, double& t_enter) const {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double near = static_cast<double>(lo[a]) - kMargin - origin_[a];
    const double far = static_cast<double>(lo[a]) + size + kMargin - origin_[a];
    if (flat_[a]) {
      if (near > 0 || far < 0) return false;
      continue;
    }
    double ta = near * inv_[a], tb = far * inv_[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  t_enter = t0;
  return t0 <= t1;
}

bool ShadowRayCaster::BrickBlocks(uint64_t brick, const std::array<uint32_t, 3>& lo) const {
  double t;
  for (uint32_t c = 0; c < 8; ++c) {
    uint32_t cell = static_cast<uint32_t>(brick >> (8 * c)) & 0xFFu;
    if (!cell) continue;
    const auto cell_lo = ChildCorner(lo, c, 2);
    if (!Enters(cell_lo, 2, t)) continue;
    for (; cell; cell &= cell - 1) {
      const auto voxel = ChildCorner(cell_lo, static_cast<uint32_t>(__builtin_ctz(cell)), 1);
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
  while (!stack_.empty()) {
    const Entry e = stack_.back();
    stack_.pop_back();
    if (e.level == brick_level) {
      if (BrickBlocks(dag_.leaves[e.ref], e.lo)) return true;
      continue;
    }
    // Children the ray reaches, nearest first: a blocker near the voxel is found early.
    struct Hit {
      double t;
      Entry entry;
    } hits[8];
    int n = 0;
    const uint32_t half = uint32_t{1} << (dag_.depth - e.level - 1);
    const uint32_t mask = dag_.Mask(e.ref);
    uint32_t child = e.ref + 1;
    for (uint32_t octant = 0; octant < 8; ++octant) {
      if (!((mask >> octant) & 1u)) continue;
      const auto lo = ChildCorner(e.lo, octant, half);
      double t;
      if (Enters(lo, half, t)) {
        Hit h{t, {dag_.nodes[child], e.level + 1, lo}};
        int i = n++;
        for (; i > 0 && hits[i - 1].t > t; --i) hits[i] = hits[i - 1];
        hits[i] = h;
      }
      ++child;
    }
    for (int i = n - 1; i >= 0; --i) stack_.push_back(hits[i].entry);
  }
  return false;
}

}  // namespace pointdag
