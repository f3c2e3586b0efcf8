// The octree and the integer transform that the hierarchical colors (colors section codec 8,
// hierarchical_colors.h) are coded over. Everything here derives from the voxels' Morton codes
// alone, so a decoder rebuilds it from decoded geometry, and every value a decoder computes is an
// integer (proto/PDAG_FORMAT.md §3): the colors are predicted from decoded neighbours, so a
// reconstruction that drifted between two decoders would drift further with every level.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/status.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag::hierarchical {

// Level l holds the distinct codes >> 3 (depth − l), ascending; level `depth` the voxels.
struct OctreeLevel {
  std::vector<uint64_t> code;
  std::vector<uint32_t> weight;       // voxels under each node
  std::vector<uint32_t> first_child;  // into level l + 1, size() + 1 entries (empty at the voxels)
  std::vector<uint8_t> child_mask;    // bit s: a child with code & 7 == s
};

struct Octree {
  int depth = 0;  // ≥ 1; the voxel codes have at most 3 × depth bits
  std::vector<OctreeLevel> level;
};

// `morton`: strictly ascending, below 2^63, fewer than 2^32 codes (else kCorrupt).
StatusOr<Octree> BuildOctree(std::span<const uint64_t> morton);

// Node index by code within one level: open addressing over a power-of-two table.
class LevelIndex {
 public:
  explicit LevelIndex(std::span<const uint64_t> codes);
  int64_t Find(uint64_t code) const;  // -1 when absent

 private:
  std::vector<uint64_t> keys_;  // code + 1; 0 = empty slot
  std::vector<uint32_t> nodes_;
  int shift_ = 64;
};

// The cell one step from `code` along Morton bit position `axis` (0..2) in direction `dir` (±1),
// on level `level`'s 2^level grid; false where that leaves the grid.
bool StepCell(uint64_t code, int axis, int dir, int level, uint64_t& out);

// Fixed point: means in 1/64 of an 8-bit level (kFractionBits), YCbCr BT.709.
constexpr int kFractionBits = 6;
using Ycc = std::array<int32_t, 3>;
// Reconstructed means and coefficient differences are clamped to these (valid streams never reach
// them; corrupt ones then cannot overflow 64 bits).
constexpr int64_t kMeanLimit = int64_t{1} << 20;
constexpr int64_t kDifferenceLimit = int64_t{1} << 22;

// round(a / b) with halves rounded up, for b > 0 and any sign of a.
constexpr int64_t DivRound(int64_t a, int64_t b) {
  const int64_t n = 2 * a + b, d = 2 * b;
  const int64_t q = n / d;
  return (n % d != 0 && n < 0) ? q - 1 : q;
}

// The step of a level `height` levels above the voxels: step16 (1/16) × 2^(height / 10), in 1/64.
int64_t LevelStep(uint32_t step16, int height);

// The quantizer step of a butterfly's mean difference for groups of wa and wb voxels: a uniform step
// `step` on the orthonormal coefficient √(wa·wb / (wa + wb)) · (mean_b − mean_a) is the step
// step · √((wa + wb) / (wa·wb)) on the difference itself. Rounded, at least 1.
int64_t DifferenceStep(int64_t step, uint64_t wa, uint64_t wb);

// The 2×2×2 butterflies of one node (RAHT's order: stage k pairs slots a and a | 1 << k, a with
// its low k + 1 bits clear; a lone b moves to a). `count` butterflies, each a pair of groups.
struct Butterfly {
  uint8_t a, b, stage;
  uint32_t wa, wb;  // the groups' voxels
};
struct NodePlan {
  struct Op {
    uint8_t a, b;
    int8_t butterfly;  // index into `butterfly`; -1: b moves to a
  };
  std::array<Op, 7> op{};
  int ops = 0;
  std::array<Butterfly, 7> butterfly{};
  int count = 0;
};
NodePlan PlanNode(uint8_t mask, std::span<const uint32_t, 8> weight);

// The butterflies' differences of group means, from the slots' means and weights (voxels): a
// merged group's mean is `divide(Σ weight × mean, Σ weight)`, rounding in the decoder's integers
// (DivRound) or exact in the encoder's doubles (its true colors); a lone slot's is its own.
template <typename T, typename Divide>
void ForwardDifferences(const NodePlan& plan, std::array<T, 8> means, std::array<T, 8> weights,
                        std::array<T, 7>& differences, Divide divide) {
  std::array<T, 8> sums{};
  std::array<bool, 8> merged{};
  const auto mean = [&](int s) { return merged[s] ? divide(sums[s], weights[s]) : means[s]; };
  for (int o = 0; o < plan.ops; ++o) {
    const NodePlan::Op& op = plan.op[o];
    if (op.butterfly >= 0) {
      differences[op.butterfly] = mean(op.b) - mean(op.a);
      if (!merged[op.a]) sums[op.a] = means[op.a] * weights[op.a];
      sums[op.a] += merged[op.b] ? sums[op.b] : means[op.b] * weights[op.b];
      weights[op.a] += weights[op.b];
      merged[op.a] = true;
    } else {
      means[op.a] = means[op.b], sums[op.a] = sums[op.b], weights[op.a] = weights[op.b], merged[op.a] = merged[op.b];
    }
  }
}
// The slots' means from the node's mean and the butterflies' differences.
void InverseMeans(const NodePlan& plan, int64_t mean, std::span<const int64_t> differences, std::array<int64_t, 8>& means);

// BT.709 YCbCr in 1/64 -> 8-bit RGB, integers only.
Rgb8 YccToRgb(const Ycc& ycc);
// 8-bit RGB -> BT.709 YCbCr in 1/64, not rounded (the encoder's true means).
std::array<double, 3> RgbToYcc(const Rgb8& rgb);

}  // namespace pointdag::hierarchical
