#include "pointdag/color/mip_colors.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace pointdag {
namespace {

constexpr uint32_t kNoParent = ~uint32_t{0};

// Walks the octree nodes in pre-order from the sorted codes: voxel i starts new nodes from the
// level where its path leaves voxel i-1's. Calls visit(level, parent) per node, in order.
template <typename Visit>
void ForEachPreorderNode(std::span<const uint64_t> morton, int depth, Visit&& visit) {
  std::array<uint32_t, 23> last_at_level{};  // pre-order index of the latest node of each level
  uint32_t next = 0;
  for (size_t i = 0; i < morton.size(); ++i) {
    int first_new = 0;
    if (i > 0) {
      const int top_bit = 63 - __builtin_clzll(morton[i] ^ morton[i - 1]);
      first_new = depth - top_bit / 3;  // levels below the deepest common ancestor are new
    }
    for (int level = first_new; level <= depth; ++level) {
      visit(level, level == 0 ? kNoParent : last_at_level[level - 1]);
      last_at_level[level] = next++;
    }
  }
}

// Calls visit(i, pre-order index of voxel i) for every voxel in order. Voxel i opens the nodes of
// the levels below its deepest common ancestor with voxel i-1, itself last, so the pre-order count
// jumps by the number of those levels: no walk over the nodes (the decoder's hot path).
template <typename Visit>
void ForEachVoxelPreorderIndex(std::span<const uint64_t> morton, int depth, Visit&& visit) {
  if (morton.empty()) return;
  // Levels opened below the deepest common ancestor, by the leading zeros of the codes' XOR (a
  // table, not a division by 3: MipVoxelColors of guanyin's tiles 13.9 -> 11.0 M Ir).
  static constexpr std::array<uint8_t, 64> kOpened = [] {
    std::array<uint8_t, 64> t{};
    for (int zeros = 0; zeros < 64; ++zeros) t[zeros] = static_cast<uint8_t>((63 - zeros) / 3 + 1);
    return t;
  }();
  uint64_t n = static_cast<uint64_t>(depth) + 1;  // nodes opened so far: the first voxel opens every level
  visit(size_t{0}, n - 1);
  for (size_t i = 1; i < morton.size(); ++i) {
    n += kOpened[__builtin_clzll(morton[i] ^ morton[i - 1])];
    visit(i, n - 1);
  }
}

}  // namespace

MipColors BuildMipColors(std::span<const uint64_t> morton, std::span<const Rgb8> colors, int depth) {
  MipColors out;
  std::vector<uint32_t> parent;
  std::vector<uint8_t> level_of;
  ForEachPreorderNode(morton, depth, [&](int level, uint32_t p) {
    if (level == depth) out.voxel_index.push_back(parent.size());
    parent.push_back(p);
    level_of.push_back(static_cast<uint8_t>(level));
  });
  // Reverse pre-order sees every child before its parent: sum children, then take the mean.
  out.colors.resize(parent.size());
  std::vector<std::array<uint32_t, 4>> sums(parent.size(), {0, 0, 0, 0});  // r, g, b, children
  size_t voxel = out.voxel_index.size();
  for (size_t n = parent.size(); n-- > 0;) {
    Rgb8 c;
    if (level_of[n] == depth) {
      c = colors[--voxel];
    } else {
      const auto& s = sums[n];
      const auto mean = [&](uint32_t sum) { return static_cast<uint8_t>((sum + s[3] / 2) / s[3]); };
      c = {mean(s[0]), mean(s[1]), mean(s[2])};
    }
    out.colors[n] = c;
    if (parent[n] != kNoParent) {
      auto& ps = sums[parent[n]];
      ps[0] += c.r, ps[1] += c.g, ps[2] += c.b, ps[3] += 1;
    }
  }
  return out;
}

std::vector<uint64_t> MipVoxelIndices(std::span<const uint64_t> morton, int depth) {
  std::vector<uint64_t> index(morton.size());
  ForEachVoxelPreorderIndex(morton, depth, [&](size_t i, uint64_t n) { index[i] = n; });
  return index;
}

StatusOr<std::vector<Rgb8>> MipVoxelColors(std::span<const uint64_t> morton, int depth, std::span<const Rgb8> mip_colors) {
  if (morton.empty()) return std::vector<Rgb8>{};
  if (mip_colors.empty()) return Corrupt(".pdag mipmap counts disagree with its voxels");
  std::vector<Rgb8> colors(morton.size());
  const uint64_t last = mip_colors.size() - 1;
  uint64_t top = 0;  // the indices increase: the last voxel's is the largest
  ForEachVoxelPreorderIndex(morton, depth, [&](size_t i, uint64_t n) {
    colors[i] = mip_colors[std::min(n, last)];
    top = n;
  });
  if (top > last) return Corrupt(".pdag mipmap counts disagree with its voxels");
  return colors;
}

}  // namespace pointdag
