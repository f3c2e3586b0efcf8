// Stage 4a: the resident Sparse Voxel DAG (Papers I and IIA) and its queries.
//
// Layout: a grid of 2^depth voxels per side. Levels 0 .. depth-3 are internal nodes stored in one
// word array `nodes`; each record is a header word followed by one child reference per set bit of
// its mask, in octant order (x<<2 | y<<1 | z). Level depth-2 holds 4x4x4 leaf bricks as 64-bit
// masks in `leaves` (bit = the voxel's 6 low Morton bits). Children of the last internal level
// refer to `leaves` by index, all others to `nodes` by word offset.
//
// Header word (Paper IIA): mask << 24 | count. `count` is the number of voxels in the subtree
// (CountMode::kLeaves) or of nodes and voxels (CountMode::kMipmap, Paper IIB, so that internal
// nodes get color indices too). Identical subtrees have identical counts, so merging them is still
// allowed. On levels whose subtrees could hold 2^24 or more (depth - level >= 8), the 24-bit field
// is an index into `upper_counts`, a separate 32-bit array, as the paper stores its upper levels.
//
// Color index (Paper IIA fig. 11): the running sum of the counts of the preceding siblings along
// the path from the root, so color i is the i-th voxel in Morton order (leaf mode) or the i-th node
// in depth-first pre-order (mipmap mode).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "pointdag/bit_count.h"
#include "pointdag/status.h"

namespace pointdag {

enum class CountMode : uint8_t { kLeaves = 0, kMipmap = 1 };

constexpr int kUpperLevelSpan = 8;  // levels with depth - level >= 8 keep counts in upper_counts

struct Svdag {
  int depth = 0;  // voxels per side = 2^depth; depth >= 2
  CountMode mode = CountMode::kLeaves;
  std::vector<uint32_t> nodes;             // internal node records, level by level, root first
  std::vector<uint32_t> level_offsets;     // word offset of each internal level's first record; size depth-2 (+1 end)
  std::vector<uint64_t> leaves;            // unique 4x4x4 bricks
  std::vector<uint32_t> upper_counts;      // counts of nodes on upper levels

  int internal_levels() const { return depth - 2; }
  bool IsUpperLevel(int level) const { return depth - level >= kUpperLevelSpan; }

  uint8_t Mask(uint32_t node) const { return static_cast<uint8_t>(nodes[node] >> 24); }
  uint64_t Count(uint32_t node, int level) const {
    const uint32_t field = nodes[node] & 0xFFFFFFu;
    return IsUpperLevel(level) ? upper_counts[field] : field;
  }
  // Total voxels (leaf mode) or nodes + voxels (mipmap mode) below the root.
  uint64_t RootCount() const;
  uint64_t VoxelCount() const;
  size_t UniqueNodeCount() const;  // internal nodes + leaf bricks

  // Resident size as the papers count it: 4-byte node words and 8-byte leaves.
  size_t ResidentBytes() const {
    return nodes.size() * 4 + leaves.size() * 8 + upper_counts.size() * 4;
  }

  bool Contains(uint32_t x, uint32_t y, uint32_t z) const;
  // Color index of voxel (x, y, z), or nothing when it is empty.
  std::optional<uint64_t> ColorIndex(uint32_t x, uint32_t y, uint32_t z) const;
  // Mipmap mode: color index of the node at `level` (0 = root .. depth = voxel) holding the cell
  // (x, y, z) of that level's grid (2^level per side), or nothing when it is empty.
  std::optional<uint64_t> MipColorIndex(uint32_t x, uint32_t y, uint32_t z, int level) const;

  // Visits every voxel in Morton order with its Morton code; the i-th call is color index i in leaf mode.
  void ForEachVoxel(const std::function<void(uint64_t morton)>& visit) const;
  std::vector<uint64_t> MortonCodes() const;

  friend bool operator==(const Svdag&, const Svdag&) = default;

  // Structural checks used after decoding untrusted bytes: every reference in range, masks
  // non-empty, counts consistent. Linear time.
  Status Validate() const;
};

// Leaf-mode count of a brick: its voxels.
inline uint64_t BrickVoxelCount(uint64_t brick) { return CountBits64(brick); }
// Mipmap-mode count of a 4x4x4 brick: itself, its occupied 2x2x2 cells (bytes), and its voxels.
inline uint64_t BrickMipCount(uint64_t brick) {
  uint64_t any = brick | brick >> 4;  // bit 0 of each byte ends as the OR of that byte's bits
  any |= any >> 2;
  any |= any >> 1;
  return 1 + CountBits64(any & 0x0101010101010101ull) + BrickVoxelCount(brick);
}

}  // namespace pointdag
