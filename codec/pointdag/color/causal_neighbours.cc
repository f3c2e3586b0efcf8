#include "pointdag/color/causal_neighbours.h"

#include <array>

namespace pointdag {

CausalNeighbours::CausalNeighbours(std::span<const uint64_t> morton) : morton_(morton), bricks_(morton) {}

void CausalNeighbours::Enter(uint64_t own) {
  constexpr int64_t kLastBrick = (int64_t{1} << (kMaxDepth - 2)) - 1;
  const auto at = MortonDecode(own);
  // Per axis, the brick coordinate moved by -1, 0, +1 spread to its Morton bits (or outside the grid).
  std::array<std::array<uint64_t, 3>, 3> spread{};
  std::array<std::array<bool, 3>, 3> inside{};
  for (int axis = 0; axis < 3; ++axis) {
    for (int d = 0; d < 3; ++d) {
      const int64_t b = int64_t{at[axis]} + d - 1;
      inside[axis][d] = b >= 0 && b <= kLastBrick;
      spread[axis][d] = inside[axis][d] ? SpreadBits3(static_cast<uint32_t>(b)) << (2 - axis) : 0;
    }
  }
  for (int dx = 0; dx < 3; ++dx) {
    for (int dy = 0; dy < 3; ++dy) {
      for (int dz = 0; dz < 3; ++dz) {
        const VoxelBrick*& near = near_[static_cast<size_t>(dx * 9 + dy * 3 + dz)];
        near = nullptr;
        if (!inside[0][dx] || !inside[1][dy] || !inside[2][dz]) continue;
        const uint64_t key = spread[0][dx] | spread[1][dy] | spread[2][dz];
        if (key <= own) near = bricks_.Find(key);  // a brick after `own` holds no voxel before its voxels
      }
    }
  }
  entered_ = own;
}

}  // namespace pointdag
