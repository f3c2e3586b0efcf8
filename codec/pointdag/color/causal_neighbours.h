// The voxels near a voxel that precede it in Morton order (decoded before it when colors are coded
// one per voxel in that order), for the lossless colors' predictions (lossless_context.h).
//
// Found through the voxels' 4x4x4 bricks (voxel_bricks.h), as weight_context.h does for the block
// colors. A box of ±2 around a voxel touches at most 2x2x2 bricks (±4: 3x3x3), of which only those
// with a code not above the voxel's own brick can hold voxels before it; each is one hash lookup,
// and the cells of the box in it one mask. Lion 1 cm, a version-2 lossless file, `pointdag decode`
// (whole process, best of 5): 0.56 s wall looking up each of the 62 candidate cells a voxel by code
// in a hash table, 0.21 s with bricks; the same colors. The 3x3x3 bricks around a voxel's own are
// looked up once per brick, not per voxel (lion 1 cm, `encode --lossless`: 3412 M -> 3313 M
// instructions).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/color/voxel_bricks.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {

class CausalNeighbours {
 public:
  // `morton`: sorted and unique (as decoded geometry enumerates the voxels); must outlive this.
  explicit CausalNeighbours(std::span<const uint64_t> morton);

  // Calls visit(j, d2) for every voxel j < i whose largest axis distance from voxel i is above
  // `inner` and at most `outer` (0 <= inner < outer <= 4), d2 its squared distance.
  template <class Visit>
  void ForEach(size_t i, int inner, int outer, Visit&& visit);

 private:
  // Fills near_ for the brick of code `own` (Morton code >> 6).
  void Enter(uint64_t own);

  std::span<const uint64_t> morton_;
  VoxelBricks bricks_;
  // The bricks around brick `entered_` at (dx + 1) * 9 + (dy + 1) * 3 + dz + 1, dx, dy, dz in
  // -1..1 (a box of ±4 voxels reaches no further): null where absent, outside or after it.
  uint64_t entered_ = UINT64_MAX;
  std::array<const VoxelBrick*, 27> near_{};
};

namespace causal_neighbours_detail {

// Cells of a brick (bits of its mask) whose coordinate on `axis` (0 x, 1 y, 2 z) lies in lo..hi.
constexpr auto kAxisRange = [] {
  std::array<std::array<std::array<uint64_t, 4>, 4>, 3> t{};
  for (int cell = 0; cell < 64; ++cell) {
    const std::array<int, 3> at = {(cell >> 2 & 1) | (cell >> 4 & 2), (cell >> 1 & 1) | (cell >> 3 & 2), (cell & 1) | (cell >> 2 & 2)};
    for (int axis = 0; axis < 3; ++axis) {
      for (int lo = 0; lo < 4; ++lo) {
        for (int hi = lo; hi < 4; ++hi) {
          if (at[axis] >= lo && at[axis] <= hi) t[axis][lo][hi] |= uint64_t{1} << cell;
        }
      }
    }
  }
  return t;
}();

// A cell's coordinates in its brick, packed as x << 4 | y << 2 | z.
constexpr auto kCellAt = [] {
  std::array<uint8_t, 64> t{};
  for (int cell = 0; cell < 64; ++cell) {
    const int x = (cell >> 2 & 1) | (cell >> 4 & 2), y = (cell >> 1 & 1) | (cell >> 3 & 2), z = (cell & 1) | (cell >> 2 & 2);
    t[cell] = static_cast<uint8_t>(x << 4 | y << 2 | z);
  }
  return t;
}();

// The cells of brick coordinate `b` on one axis within v - r .. v + r (v, r in voxels), clipped.
inline uint64_t AxisCells(int axis, int64_t v, int r, int64_t b) {
  const int64_t lo = std::max<int64_t>(v - r - 4 * b, 0), hi = std::min<int64_t>(v + r - 4 * b, 3);
  return lo > hi ? 0 : kAxisRange[axis][lo][hi];
}

}  // namespace causal_neighbours_detail

template <class Visit>
void CausalNeighbours::ForEach(size_t i, int inner, int outer, Visit&& visit) {
  using namespace causal_neighbours_detail;
  const uint64_t code = morton_[i], own = code >> 6;
  if (own != entered_) Enter(own);
  const auto [x, y, z] = MortonDecode(code);
  const int64_t v[3] = {x, y, z};
  constexpr int64_t kLastBrick = (int64_t{1} << (kMaxDepth - 2)) - 1;
  int64_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max<int64_t>(v[a] - outer, 0) >> 2;
    hi[a] = std::min<int64_t>((v[a] + outer) >> 2, kLastBrick);
  }
  const int64_t ox = x >> 2, oy = y >> 2, oz = z >> 2;
  for (int64_t bx = lo[0]; bx <= hi[0]; ++bx) {
    for (int64_t by = lo[1]; by <= hi[1]; ++by) {
      for (int64_t bz = lo[2]; bz <= hi[2]; ++bz) {
        const VoxelBrick* brick = near_[static_cast<size_t>((bx - ox + 1) * 9 + (by - oy + 1) * 3 + (bz - oz + 1))];
        if (brick == nullptr) continue;
        uint64_t cells = AxisCells(0, x, outer, bx) & AxisCells(1, y, outer, by) & AxisCells(2, z, outer, bz);
        cells &= ~(AxisCells(0, x, inner, bx) & AxisCells(1, y, inner, by) & AxisCells(2, z, inner, bz));
        if (brick->code == own) cells &= (uint64_t{1} << (code & 63)) - 1;
        for (uint64_t m = cells & brick->cells; m != 0; m &= m - 1) {
          const int cell = std::countr_zero(m);
          const uint32_t j = brick->IndexOf(cell);
          const int at = kCellAt[cell];
          const int64_t dx = 4 * bx + (at >> 4) - v[0], dy = 4 * by + (at >> 2 & 3) - v[1], dz = 4 * bz + (at & 3) - v[2];
          visit(size_t{j}, static_cast<int>(dx * dx + dy * dy + dz * dz));
        }
      }
    }
  }
}

}  // namespace pointdag
