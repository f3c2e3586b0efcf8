// The voxels' 4x4x4 bricks (Morton code >> 6), through which the color coders find the neighbours
// that precede a voxel in Morton order (weight_context.h, causal_neighbours.h): per brick, its
// first voxel's index and a 64-bit mask of its cells, so a voxel's index is its brick's first index
// plus the cells before it in the mask. Bricks are found by code in a hash table (a gallop and
// bisection over the sorted bricks cost the weight contexts twice the instructions).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/bit_count.h"

namespace pointdag {

struct VoxelBrick {
  uint64_t code;   // Morton code >> 6
  uint32_t first;  // index of its first voxel
  uint64_t cells;  // bit (Morton code & 63) per voxel

  // The index of the voxel in `cell` (0..63, one of `cells`).
  uint32_t IndexOf(int cell) const { return first + CountBits64(cells & ((uint64_t{1} << cell) - 1)); }
};

class VoxelBricks {
 public:
  // `morton`: sorted and unique (as decoded geometry enumerates the voxels).
  explicit VoxelBricks(std::span<const uint64_t> morton);

  // In code order.
  const std::vector<VoxelBrick>& all() const { return bricks_; }
  // The brick of `code`, else null.
  const VoxelBrick* Find(uint64_t code) const;

 private:
  static uint64_t Hash(uint64_t code) { return (code * 0x9E3779B97F4A7C15ull) >> 24; }

  std::vector<VoxelBrick> bricks_;
  std::vector<uint32_t> slots_;  // open addressing: brick index + 1, 0 = empty
  uint64_t mask_ = 0;
};

}  // namespace pointdag
