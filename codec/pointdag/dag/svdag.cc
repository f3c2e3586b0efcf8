#include "pointdag/dag/svdag.h"

#include <string>

#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

int Popcount8(uint32_t v) { return __builtin_popcount(v & 0xFFu); }

uint32_t Octant(uint32_t x, uint32_t y, uint32_t z, int shift) {
  return ((x >> shift) & 1u) << 2 | ((y >> shift) & 1u) << 1 | ((z >> shift) & 1u);
}

// Mipmap pre-order rank inside a brick of the 2x2x2 cell `cell` (at level depth-1) or, with
// voxel_bit >= 0, of that voxel (the brick node itself is rank 0).
uint64_t BrickMipRank(uint64_t brick, uint32_t cell, int voxel_bit) {
  uint64_t rank = 1;
  for (uint32_t c = 0; c < cell; ++c) {
    const uint32_t sub = static_cast<uint32_t>(brick >> (8 * c)) & 0xFFu;
    if (sub) rank += 1 + static_cast<uint64_t>(Popcount8(sub));
  }
  if (voxel_bit >= 0) {
    const uint32_t sub = static_cast<uint32_t>(brick >> (8 * cell)) & 0xFFu;
    rank += 1 + static_cast<uint64_t>(Popcount8(sub & ((1u << (voxel_bit & 7)) - 1)));
  }
  return rank;
}

// Count of the node referenced by `ref` on `level`, whatever kind of node that level holds.
uint64_t RefCount(const Svdag& dag, uint32_t ref, int level) {
  if (level == dag.depth - 2) {
    return dag.mode == CountMode::kMipmap ? BrickMipCount(dag.leaves[ref]) : BrickVoxelCount(dag.leaves[ref]);
  }
  return dag.Count(ref, level);
}

// Walks from the root towards the cell (x, y, z) of level `target` (grid 2^target per side) and
// returns its color index, or nothing when the cell is empty. Leaf mode supports target == depth only.
std::optional<uint64_t> Locate(const Svdag& dag, uint32_t x, uint32_t y, uint32_t z, int target) {
  const bool mip = dag.mode == CountMode::kMipmap;
  if (target < 0 || target > dag.depth) return std::nullopt;
  const uint64_t side = uint64_t{1} << target;
  if (x >= side || y >= side || z >= side) return std::nullopt;
  // Express the cell in the finest grid so that bit (depth-1-level) picks the child at `level`.
  const int up = dag.depth - target;
  x <<= up, y <<= up, z <<= up;

  uint64_t index = 0;
  uint32_t ref = 0;
  for (int level = 0; level < dag.depth - 2; ++level) {
    if (level == target) return index;
    const uint32_t mask = dag.Mask(ref);
    const uint32_t octant = Octant(x, y, z, dag.depth - 1 - level);
    if (!((mask >> octant) & 1u)) return std::nullopt;
    const int rank = Popcount8(mask & ((1u << octant) - 1));
    for (int i = 0; i < rank; ++i) index += RefCount(dag, dag.nodes[ref + 1 + i], level + 1);
    if (mip) index += 1;
    ref = dag.nodes[ref + 1 + rank];
  }
  // Brick level: depth-2 is the brick itself, depth-1 one of its 2x2x2 cells, depth a voxel.
  const uint64_t brick = dag.leaves[ref];
  if (target == dag.depth - 2) return index;
  const uint32_t cell = Octant(x, y, z, 1);
  if (!((brick >> (8 * cell)) & 0xFFu)) return std::nullopt;
  if (target == dag.depth - 1) return index + BrickMipRank(brick, cell, -1);
  const int bit = static_cast<int>(cell << 3 | Octant(x, y, z, 0));
  if (!((brick >> bit) & 1u)) return std::nullopt;
  if (mip) return index + BrickMipRank(brick, cell, bit);
  return index + static_cast<uint64_t>(__builtin_popcountll(brick & ((uint64_t{1} << bit) - 1)));
}

// A template, not a std::function: MortonCodes' push per voxel inlines (an indirect call per voxel
// was 4 % of a tile's decode).
template <typename Visit>
void VisitVoxels(const Svdag& dag, uint32_t ref, int level, uint64_t prefix, Visit& visit) {
  if (level == dag.depth - 2) {
    for (uint64_t brick = dag.leaves[ref]; brick; brick &= brick - 1) {
      visit(prefix << 6 | static_cast<uint64_t>(__builtin_ctzll(brick)));
    }
    return;
  }
  const uint32_t* child = &dag.nodes[ref + 1];
  for (uint32_t mask = dag.Mask(ref); mask; mask &= mask - 1, ++child) {
    VisitVoxels(dag, *child, level + 1, prefix << 3 | static_cast<uint64_t>(__builtin_ctz(mask)), visit);
  }
}

}  // namespace

uint64_t Svdag::RootCount() const { return RefCount(*this, 0, 0); }

uint64_t Svdag::VoxelCount() const {
  if (mode == CountMode::kLeaves) return RefCount(*this, 0, 0);
  uint64_t n = 0;  // mipmap counts include internal nodes, so count the voxels themselves
  ForEachVoxel([&n](uint64_t) { ++n; });
  return n;
}

size_t Svdag::UniqueNodeCount() const {
  size_t internal = 0;
  for (size_t w = 0; w < nodes.size(); w += 1 + static_cast<size_t>(Popcount8(nodes[w] >> 24))) ++internal;
  return internal + leaves.size();
}

bool Svdag::Contains(uint32_t x, uint32_t y, uint32_t z) const { return ColorIndex(x, y, z).has_value(); }

std::optional<uint64_t> Svdag::ColorIndex(uint32_t x, uint32_t y, uint32_t z) const {
  return Locate(*this, x, y, z, depth);
}

std::optional<uint64_t> Svdag::MipColorIndex(uint32_t x, uint32_t y, uint32_t z, int level) const {
  if (mode != CountMode::kMipmap) return std::nullopt;
  return Locate(*this, x, y, z, level);
}

void Svdag::ForEachVoxel(const std::function<void(uint64_t)>& visit) const {
  if (leaves.empty()) return;
  VisitVoxels(*this, 0, 0, 0, visit);
}

std::vector<uint64_t> Svdag::MortonCodes() const {
  std::vector<uint64_t> codes;
  if (leaves.empty()) return codes;
  auto push = [&](uint64_t code) { codes.push_back(code); };
  VisitVoxels(*this, 0, 0, 0, push);
  return codes;
}

Status Svdag::Validate() const {
  if (depth < 2 || depth > kMaxDepth) return Corrupt("DAG depth " + std::to_string(depth) + " is outside 2..21");
  if (leaves.empty()) return Corrupt("DAG has no leaf bricks");
  for (uint64_t brick : leaves) {
    if (brick == 0) return Corrupt("DAG has an empty leaf brick");
  }
  const int levels = internal_levels();
  if (levels == 0) {
    if (!nodes.empty() || leaves.size() != 1) return Corrupt("a depth-2 DAG is exactly one brick");
    return Status::Ok();
  }
  if (level_offsets.size() != static_cast<size_t>(levels) + 1 || level_offsets[0] != 0 ||
      level_offsets[levels] != nodes.size()) {
    return Corrupt("DAG level table does not match its node array");
  }
  // Pass 1: every level parses into whole records; remember where records start.
  std::vector<bool> record_start(nodes.size() + 1, false);
  for (int level = 0; level < levels; ++level) {
    size_t w = level_offsets[level];
    if (w > level_offsets[level + 1]) return Corrupt("DAG level offsets are not increasing");
    while (w < level_offsets[level + 1]) {
      const uint32_t mask = nodes[w] >> 24;
      if (mask == 0) return Corrupt("DAG node with an empty child mask");
      record_start[w] = true;
      w += 1 + static_cast<size_t>(Popcount8(mask));
    }
    if (w != level_offsets[level + 1]) return Corrupt("DAG node record overruns its level");
  }
  if (level_offsets[1] == 0 || nodes[0] >> 24 == 0) return Corrupt("DAG has no root");
  // Pass 2, bottom-up: references land on records of the next level; counts add up.
  for (int level = levels - 1; level >= 0; --level) {
    for (size_t w = level_offsets[level]; w < level_offsets[level + 1];) {
      const uint32_t mask = nodes[w] >> 24;
      const int children = Popcount8(mask);
      uint64_t sum = mode == CountMode::kMipmap ? 1 : 0;
      for (int i = 0; i < children; ++i) {
        const uint32_t ref = nodes[w + 1 + i];
        if (level + 1 == levels) {
          if (ref >= leaves.size()) return Corrupt("DAG leaf reference out of range");
        } else if (ref < level_offsets[level + 1] || ref >= level_offsets[level + 2] || !record_start[ref]) {
          return Corrupt("DAG child reference does not point at a node of the next level");
        }
        sum += RefCount(*this, ref, level + 1);
      }
      if (IsUpperLevel(level) && (nodes[w] & 0xFFFFFFu) >= upper_counts.size()) {
        return Corrupt("DAG upper-level count index out of range");
      }
      if (Count(static_cast<uint32_t>(w), level) != sum) return Corrupt("DAG node count disagrees with its children");
      w += 1 + static_cast<size_t>(children);
    }
  }
  return Status::Ok();
}

}  // namespace pointdag
