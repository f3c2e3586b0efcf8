// Open addressing from a voxel's Morton code to its color index (the voxel's Morton rank), for the
// color coders that find a voxel's decoded neighbours by code: the lossless colors' neighbour mode
// (lossless_context.cc) and the block stream's weight contexts (weight_context.h). Keys are read
// back from the codes themselves, so a slot is one index (+1, 0 = empty).
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>
#include <vector>

namespace pointdag {

class MortonTable {
 public:
  // `morton`: unique codes, fewer than 2^32; must outlive the table.
  explicit MortonTable(std::span<const uint64_t> morton) : morton_(morton) {
    const size_t capacity = std::bit_ceil(std::max<size_t>(16, 2 * morton.size()));
    slots_.assign(capacity, 0);
    mask_ = capacity - 1;
    for (size_t i = 0; i < morton.size(); ++i) {
      size_t s = Hash(morton[i]) & mask_;
      while (slots_[s] != 0) s = (s + 1) & mask_;
      slots_[s] = static_cast<uint32_t>(i + 1);
    }
  }
  // The index of `code`, or -1.
  int64_t Find(uint64_t code) const {
    for (size_t s = Hash(code) & mask_; slots_[s] != 0; s = (s + 1) & mask_) {
      if (morton_[slots_[s] - 1] == code) return slots_[s] - 1;
    }
    return -1;
  }

 private:
  static size_t Hash(uint64_t code) { return static_cast<size_t>((code * 0x9E3779B97F4A7C15ull) >> 20); }
  std::span<const uint64_t> morton_;
  std::vector<uint32_t> slots_;
  size_t mask_ = 0;
};

}  // namespace pointdag
