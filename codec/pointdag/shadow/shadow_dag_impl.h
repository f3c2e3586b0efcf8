// Inside a ShadowDag (shadow_dag.h): the resident arrays shared by the builder, the queries and
// the byte form (proto/SHADOW_FORMAT.md §1).
//
// Levels 0 .. light_depth-3 are internal nodes in one word array, root first, level by level. A
// record is a header word, pointer_mask | full_mask << 8, then one word per bit of pointer_mask in
// octant order (x<<2 | y<<1 | z): the child's word offset, or on the last internal level its index
// in `leaves`. A child that is not a pointer is all shadowed when its full_mask bit is set, else
// all lit. `leaves` are 4x4x4 bricks, bit = the cell's 6 low Morton bits, 1 = shadowed.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pointdag/shadow/light_frame.h"
#include "pointdag/shadow/shadow_dag.h"

namespace pointdag {

enum class ShadowRoot : uint8_t { kLit = 0, kShadowed = 1, kNode = 2 };

struct ShadowDag::Impl {
  LightFrame frame;
  bool below_horizon = false;
  ShadowRoot root = ShadowRoot::kLit;
  std::vector<uint32_t> nodes;
  std::vector<uint64_t> leaves;
  ShadowDagStats stats;

  bool Shadowed(const std::array<double, 3>& grid_point) const;
  // shadow_dag_bytes, dense_grid_bytes, shadow_map_bytes and light_depth from the arrays and frame.
  void FillSizeStats();
};

// The DAG of the defined cells: light-space Morton codes (light_depth levels) shifted left by one,
// the low bit 1 = shadowed, sorted by strictly increasing code. Every other cell is undefined.
// Fills everything but the frame, below_horizon, and the voxel counts of the stats.
Status BuildShadowArrays(std::span<const uint64_t> defined_cells, int light_depth, const ShadowBuildOptions& options,
                         ShadowDag::Impl& out);

class ShadowTreeBuilder;

// The same build fed whole subtrees in increasing Morton order, each all lit, all shadowed or a
// brick, with nothing undefined (the free-space mode, shadow_free_space.h).
class ShadowSubtreeSink {
 public:
  ShadowSubtreeSink(int light_depth, const ShadowBuildOptions& options);
  ~ShadowSubtreeSink();
  void Uniform(int height, uint64_t key, bool shadowed);  // height 2 .. light_depth
  void Brick(uint64_t key, uint64_t mask);                // mask bit = the cell's 6 low Morton bits
  void Finish(ShadowDag::Impl& out);

 private:
  std::unique_ptr<ShadowTreeBuilder> builder_;
};

// The free-space mode (shadow_free_space.cc): arrays for out.frame where every cell outside the
// voxel cubes is defined too; `centre_cells` as for BuildShadowArrays.
Status BuildFreeSpaceArrays(const Svdag& dag, std::span<const uint64_t> centre_cells, const ShadowBuildOptions& options,
                            ShadowDag::Impl& out);

}  // namespace pointdag
