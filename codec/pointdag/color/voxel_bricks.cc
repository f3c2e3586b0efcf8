#include "pointdag/color/voxel_bricks.h"

#include <algorithm>
#include <bit>

namespace pointdag {

VoxelBricks::VoxelBricks(std::span<const uint64_t> morton) {
  for (size_t i = 0; i < morton.size(); ++i) {
    const uint64_t code = morton[i] >> 6;
    if (bricks_.empty() || bricks_.back().code != code) bricks_.push_back({code, static_cast<uint32_t>(i), 0});
    bricks_.back().cells |= uint64_t{1} << (morton[i] & 63);
  }
  const size_t capacity = std::bit_ceil(std::max<size_t>(16, 2 * bricks_.size()));
  slots_.assign(capacity, 0);
  mask_ = capacity - 1;
  for (size_t k = 0; k < bricks_.size(); ++k) {
    uint64_t s = Hash(bricks_[k].code) & mask_;
    while (slots_[s] != 0) s = (s + 1) & mask_;
    slots_[s] = static_cast<uint32_t>(k + 1);
  }
}

const VoxelBrick* VoxelBricks::Find(uint64_t code) const {
  for (uint64_t s = Hash(code) & mask_; slots_[s] != 0; s = (s + 1) & mask_) {
    const VoxelBrick& brick = bricks_[slots_[s] - 1];
    if (brick.code == code) return &brick;
  }
  return nullptr;
}

}  // namespace pointdag
