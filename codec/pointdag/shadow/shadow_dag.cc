#include "pointdag/shadow/shadow_dag.h"

#include <cmath>

#include "pointdag/shadow/shadow_dag_impl.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {

ShadowDag::ShadowDag() : impl_(std::make_unique<Impl>()) {}
ShadowDag::ShadowDag(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ShadowDag::ShadowDag(ShadowDag&&) noexcept = default;
ShadowDag& ShadowDag::operator=(ShadowDag&&) noexcept = default;
ShadowDag::~ShadowDag() = default;

bool ShadowDag::Shadowed(const std::array<double, 3>& grid_point) const { return impl_->Shadowed(grid_point); }

const ShadowDagStats& ShadowDag::stats() const { return impl_->stats; }

bool ShadowDag::Impl::Shadowed(const std::array<double, 3>& grid_point) const {
  if (below_horizon) return true;
  if (root == ShadowRoot::kLit) return false;
  const auto cell = frame.Cell(grid_point);
  if (!cell) return false;  // outside the light cube, so outside the dataset's grid
  if (root == ShadowRoot::kShadowed) return true;
  const auto [x, y, z] = *cell;
  const int depth = frame.light_depth();
  uint32_t node = 0;
  for (int level = 0;; ++level) {
    const int shift = depth - 1 - level;
    const uint32_t octant = ((x >> shift) & 1) << 2 | ((y >> shift) & 1) << 1 | ((z >> shift) & 1);
    const uint32_t header = nodes[node];
    if (((header >> octant) & 1) == 0) return (header >> (8 + octant)) & 1;
    const uint32_t child = nodes[node + 1 + __builtin_popcount(header & 0xFFu & ((1u << octant) - 1))];
    if (level == depth - 3) return (leaves[child] >> MortonEncode(x & 3, y & 3, z & 3)) & 1;
    node = child;
  }
}

void ShadowDag::Impl::FillSizeStats() {
  const int depth = frame.light_depth();
  stats.light_depth = depth;
  stats.shadow_dag_bytes = nodes.size() * 4 + leaves.size() * 8;
  // 2^(3·depth) bits and 4 · 2^(2·depth) bytes fit in 64 bits for depth <= 21.
  stats.dense_grid_bytes = depth >= 1 ? uint64_t{1} << (3 * depth - 3) : 1;
  stats.shadow_map_bytes = uint64_t{4} << (2 * depth);
}

}  // namespace pointdag
