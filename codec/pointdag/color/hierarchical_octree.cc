#include "pointdag/color/hierarchical_octree.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace pointdag::hierarchical {
namespace {

constexpr uint64_t kAxisBits = 0x1249249249249249ull;  // bit positions 0, 3, 6, ...

// 4096 × 2^(h / 10), rounded: the per-level growth of the step (coarser coefficients high in the tree).
constexpr std::array<int64_t, 22> kLevelGrowth = {4096,  4390,  4705,  5043,  5405,  5793,  6208,  6654,
                                                  7132,  7643,  8192,  8780,  9410,  10086, 10809, 11585,
                                                  12417, 13308, 14263, 15287, 16384, 17560};

__extension__ typedef unsigned __int128 u128;  // GCC and Clang (emscripten too) have it

uint64_t IntegerSqrt(u128 x) {
  uint64_t r = static_cast<uint64_t>(std::sqrt(static_cast<double>(x)));
  while (static_cast<u128>(r) * r > x) --r;
  while (static_cast<u128>(r + 1) * (r + 1) <= x) ++r;
  return r;
}

}  // namespace

StatusOr<Octree> BuildOctree(std::span<const uint64_t> morton) {
  if (morton.empty()) return Corrupt("hierarchical colors need at least one voxel");
  if (morton.size() >= (uint64_t{1} << 32)) return ResourceLimit("hierarchical colors hold fewer than 2^32 voxels");
  for (size_t i = 1; i < morton.size(); ++i) {
    if (morton[i] <= morton[i - 1]) return Corrupt("voxel Morton codes are not strictly ascending");
  }
  if (morton.back() >> 63) return Corrupt("a voxel Morton code has more than 63 bits");
  Octree tree;
  tree.depth = std::max(1, static_cast<int>((std::bit_width(morton.back()) + 2) / 3));
  tree.level.resize(tree.depth + 1);
  OctreeLevel& voxels = tree.level[tree.depth];
  voxels.code.assign(morton.begin(), morton.end());
  voxels.weight.assign(morton.size(), 1);
  for (int l = tree.depth - 1; l >= 0; --l) {
    const OctreeLevel& children = tree.level[l + 1];
    OctreeLevel& nodes = tree.level[l];
    for (size_t j = 0; j < children.code.size(); ++j) {
      const uint64_t parent = children.code[j] >> 3;
      if (nodes.code.empty() || nodes.code.back() != parent) {
        nodes.code.push_back(parent);
        nodes.weight.push_back(0);
        nodes.first_child.push_back(static_cast<uint32_t>(j));
        nodes.child_mask.push_back(0);
      }
      nodes.weight.back() += children.weight[j];
      nodes.child_mask.back() |= static_cast<uint8_t>(1u << (children.code[j] & 7));
    }
    nodes.first_child.push_back(static_cast<uint32_t>(children.code.size()));
  }
  return tree;
}

LevelIndex::LevelIndex(std::span<const uint64_t> codes) {
  const int bits = std::max(4, static_cast<int>(std::bit_width(codes.size() * 2)));
  keys_.assign(size_t{1} << bits, 0);
  nodes_.resize(keys_.size());
  shift_ = 64 - bits;
  const uint64_t mask = keys_.size() - 1;
  for (size_t i = 0; i < codes.size(); ++i) {
    uint64_t slot = (codes[i] * 0x9E3779B97F4A7C15ull) >> shift_;
    while (keys_[slot] != 0) slot = (slot + 1) & mask;
    keys_[slot] = codes[i] + 1;
    nodes_[slot] = static_cast<uint32_t>(i);
  }
}

int64_t LevelIndex::Find(uint64_t code) const {
  const uint64_t mask = keys_.size() - 1;
  for (uint64_t slot = (code * 0x9E3779B97F4A7C15ull) >> shift_;; slot = (slot + 1) & mask) {
    if (keys_[slot] == code + 1) return nodes_[slot];
    if (keys_[slot] == 0) return -1;
  }
}

bool StepCell(uint64_t code, int axis, int dir, int level, uint64_t& out) {
  const uint64_t grid = level >= 21 ? ~uint64_t{0} >> 1 : (uint64_t{1} << (3 * level)) - 1;
  const uint64_t m = (kAxisBits << axis) & grid;
  const uint64_t along = code & m;
  if (dir > 0) {
    if (along == m) return false;
    out = (code & ~m) | (((code | ~m) + (uint64_t{1} << axis)) & m);  // dilated increment
  } else {
    if (along == 0) return false;
    out = (code & ~m) | ((along - (uint64_t{1} << axis)) & m);
  }
  return true;
}

int64_t LevelStep(uint32_t step16, int height) {
  const int64_t growth = kLevelGrowth[std::clamp(height, 0, static_cast<int>(kLevelGrowth.size()) - 1)];
  return std::max<int64_t>(1, (int64_t{step16} * 4 * growth + 2048) >> 12);
}

int64_t DifferenceStep(int64_t step, uint64_t wa, uint64_t wb) {
  const u128 x = (static_cast<u128>(step) * static_cast<u128>(step) * (wa + wb) << 32) / (static_cast<u128>(wa) * wb);
  return std::max<int64_t>(1, static_cast<int64_t>((IntegerSqrt(x) + (1u << 15)) >> 16));
}

NodePlan PlanNode(uint8_t mask, std::span<const uint32_t, 8> weight) {
  NodePlan plan;
  std::array<uint32_t, 8> w;
  std::copy(weight.begin(), weight.end(), w.begin());
  uint32_t present = mask;
  for (int k = 0; k < 3; ++k) {
    for (int a = 0; a < 8; a += 2 << k) {
      const int b = a | 1 << k;
      const bool has_a = (present >> a) & 1, has_b = (present >> b) & 1;
      if (has_a && has_b) {
        plan.butterfly[plan.count] = {static_cast<uint8_t>(a), static_cast<uint8_t>(b), static_cast<uint8_t>(k), w[a], w[b]};
        plan.op[plan.ops++] = {static_cast<uint8_t>(a), static_cast<uint8_t>(b), static_cast<int8_t>(plan.count++)};
        w[a] += w[b];
      } else if (has_b) {
        plan.op[plan.ops++] = {static_cast<uint8_t>(a), static_cast<uint8_t>(b), -1};
        w[a] = w[b];
        present |= 1u << a;
      }
      present &= ~(1u << b);
    }
  }
  return plan;
}

void InverseMeans(const NodePlan& plan, int64_t mean, std::span<const int64_t> differences, std::array<int64_t, 8>& means) {
  means[0] = mean;
  for (int o = plan.ops - 1; o >= 0; --o) {
    const NodePlan::Op& op = plan.op[o];
    if (op.butterfly < 0) {
      means[op.b] = means[op.a];
      continue;
    }
    const Butterfly& bf = plan.butterfly[op.butterfly];
    const int64_t d = differences[op.butterfly];
    // The group's mean splits so that wa·mean_a + wb·mean_b keeps it and mean_b − mean_a = d.
    means[op.b] = std::clamp(means[op.a] + DivRound(int64_t{bf.wa} * d, int64_t{bf.wa} + bf.wb), -kMeanLimit, kMeanLimit);
    means[op.a] = std::clamp(means[op.b] - d, -kMeanLimit, kMeanLimit);
  }
}

Rgb8 YccToRgb(const Ycc& ycc) {
  const int64_t y = ycc[0], cb = ycc[1], cr = ycc[2];
  // R = Y + 1.5748 Cr, B = Y + 1.8556 Cb, G = Y − 0.46812 Cr − 0.18732 Cb (coefficients in 1/65536).
  const int64_t r = y + ((cr * 103206 + 32768) >> 16);
  const int64_t b = y + ((cb * 121609 + 32768) >> 16);
  const int64_t g = y - ((cr * 30679 + cb * 12276 + 32768) >> 16);
  const auto to8 = [](int64_t v) { return static_cast<uint8_t>(std::clamp<int64_t>((v + 32) >> kFractionBits, 0, 255)); };
  return {to8(r), to8(g), to8(b)};
}

std::array<double, 3> RgbToYcc(const Rgb8& rgb) {
  const double y = 0.2126 * rgb.r + 0.7152 * rgb.g + 0.0722 * rgb.b;
  constexpr double kScale = 1 << kFractionBits;
  return {y * kScale, (rgb.b - y) / 1.8556 * kScale, (rgb.r - y) / 1.5748 * kScale};
}

}  // namespace pointdag::hierarchical
