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

// Set bits of each byte: a child's rank among its siblings (the build has no popcnt instruction).
constexpr std::array<uint8_t, 256> kBits = [] {
  std::array<uint8_t, 256> bits{};
  for (int i = 1; i < 256; ++i) bits[i] = static_cast<uint8_t>(bits[i >> 1] + (i & 1));
  return bits;
}();

std::array<uint32_t, 3> ChildCorner(const std::array<uint32_t, 3>& lo, uint32_t octant, uint32_t half) {
  return {lo[0] + ((octant >> 2) & 1u) * half, lo[1] + ((octant >> 1) & 1u) * half, lo[2] + (octant & 1u) * half};
}

}  // namespace

ShadowRayCaster::ShadowRayCaster(const Svdag& dag, const std::array<double, 3>& travel, double bias)
    : dag_(dag), travel_(travel), bias_(bias) {
  for (int a = 0; a < 3; ++a) {
    flat_[a] = travel[a] == 0;
    inv_[a] = flat_[a] ? 0 : -1 / travel[a];
    if (travel[a] > 0) flip_ |= 1u << (2 - a);  // the ray runs towards lower coordinates
  }
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
      if (voxel != self_ && RayMeetsCell(origin_, travel_, voxel, bias_)) return true;
    }
  }
  return false;
}

void ShadowRayCaster::FindOwnBrick(const std::array<uint32_t, 3>& voxel) {
  const std::array<uint32_t, 3> lo{voxel[0] & ~3u, voxel[1] & ~3u, voxel[2] & ~3u};
  if (lo == own_lo_) return;
  uint32_t ref = 0;
  for (int level = 0; level < dag_.depth - 2; ++level) {
    const int shift = dag_.depth - 1 - level;
    const uint32_t octant = ((voxel[0] >> shift) & 1u) << 2 | ((voxel[1] >> shift) & 1u) << 1 | ((voxel[2] >> shift) & 1u);
    ref = dag_.nodes[ref + 1 + kByteBits[dag_.Mask(ref) & ((1u << octant) - 1)]];
  }
  own_lo_ = lo;
  own_ref_ = ref;
}

bool ShadowRayCaster::Blocked(const std::array<uint32_t, 3>& voxel) {
  if (dag_.leaves.empty()) return false;
  self_ = voxel;
  for (int a = 0; a < 3; ++a) origin_[a] = voxel[a] + 0.5;
  FindOwnBrick(voxel);
  if (BrickBlocks(dag_.leaves[own_ref_], own_lo_)) return true;
  const int brick_level = dag_.depth - 2;
  size_t top = 0;
  stack_[top++] = {0, 0, {0, 0, 0}};
  ChildSlabs slabs;
  while (top) {
    const Entry e = stack_[--top];
    if (e.level == brick_level) {
      if (e.lo != own_lo_ && BrickBlocks(dag_.leaves[e.ref], e.lo)) return true;
      continue;
    }
    const uint32_t half = uint32_t{1} << (dag_.depth - e.level - 1);
    const uint32_t mask = dag_.Mask(e.ref);
    Slabs(e.lo, half, slabs);
    // Pushed farthest first so that the nearest child is taken next.
    for (int i = 7; i >= 0; --i) {
      const uint32_t octant = static_cast<uint32_t>(i) ^ flip_;
      if (!((mask >> octant) & 1u) || !slabs.Reach(octant)) continue;
      const uint32_t rank = kByteBits[mask & ((1u << octant) - 1)];
      stack_[top++] = {dag_.nodes[e.ref + 1 + rank], e.level + 1, ChildCorner(e.lo, octant, half)};
    }
  }
  return false;
}

}  // namespace pointdag
