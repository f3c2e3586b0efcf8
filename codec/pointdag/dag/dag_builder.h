// Stage 4b: building the SVDAG (Paper I, hash-based, with Paper IIA/IIB counts).
//
// How: voxels arrive sorted by Morton code, so the octree is walked bottom-up in one streaming
// pass without ever materialising the SVO. Each finished subtree gets a 64-bit hash computed from
// its contents (a brick's 64-bit mask; a node's mask and its children's hashes, as in Paper I,
// fig. 10) and is interned: a hash hit is only a candidate, confirmed by comparing the mask and
// the children's canonical ids, which for already-unique children is a full subtree comparison.
// A hash collision can therefore cost time, never correctness. A final top-down pass from the root
// emits the unique nodes breadth-first in first-seen order, which makes the output canonical:
// the same voxels give the same arrays whichever way they were built.
//
// Merge (Paper I): sub-DAGs of disjoint spatial chunks are interned into one builder in a single
// sweep over their nodes, bottom-up; their roots then join the streaming pass as ordinary
// subtrees. BuildDagChunked() uses this to keep only one chunk's temporaries alive at a time.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "pointdag/dag/svdag.h"

namespace pointdag::gpu {
class VulkanContext;
}

namespace pointdag {

struct DagBuildOptions {
  CountMode mode = CountMode::kLeaves;
  // Bits of the subtree hash that are kept. Tests narrow it to force collisions; results must not
  // change, only speed.
  uint64_t hash_mask = ~uint64_t{0};
};

// DAG of sorted, unique Morton codes on a grid of 2^depth per side (depth 2..21). The subtree
// hashes come from the Vulkan kernels where DagHashesDevice() says so (the same hashes, so the
// same DAG).
StatusOr<Svdag> BuildDag(std::span<const uint64_t> morton, int depth, const DagBuildOptions& options = {});

// Where BuildDag hashes subtrees in this process (null: the CPU), per gpu/pointdag/gpu/stage_device.h;
// under POINTDAG_DEVICE=auto decided on the first call by timing both paths.
StatusOr<gpu::VulkanContext*> DagHashesDevice();

// A sub-DAG whose root is the cell `prefix` (its Morton code on level depth - dag->depth).
struct PlacedSubdag {
  const Svdag* dag = nullptr;
  uint64_t prefix = 0;
};

// Incremental merge (Paper I): sub-DAGs of the cells of level `chunk_levels`, added in increasing
// Morton order, become one DAG of the whole depth-`depth` grid. Memory: the unique nodes so far.
class DagMerger {
 public:
  static StatusOr<DagMerger> Create(int depth, int chunk_levels, const DagBuildOptions& options = {});
  DagMerger(DagMerger&&) noexcept;
  ~DagMerger();

  // A sub-DAG of depth (depth - chunk_levels) whose root is cell `prefix` of level chunk_levels.
  Status AddSubdag(const Svdag& sub, uint64_t prefix);
  // Builds and adds the sub-DAG of one chunk from its voxels (sorted global Morton codes, one cell);
  // with chunk_levels 0 the voxels stream straight into the DAG.
  Status AddChunk(std::span<const uint64_t> codes);
  StatusOr<Svdag> Finish();

  class Impl;

 private:
  DagMerger(int depth, int chunk_levels, const DagBuildOptions& options);
  std::unique_ptr<Impl> impl_;
  int depth_;
  int chunk_levels_;
  DagBuildOptions options_;
  bool added_any_ = false;
  uint64_t last_prefix_ = 0;
};

// Merges sub-DAGs of disjoint cells, in increasing prefix order, all of the same depth and mode,
// into the DAG of the whole depth-`depth` grid.
StatusOr<Svdag> MergeSubdags(std::span<const PlacedSubdag> parts, int depth, const DagBuildOptions& options = {});

// Same result as BuildDag(), built chunk by chunk: the grid is cut into the 8^chunk_levels cells
// of level chunk_levels, each built as its own sub-DAG and merged in at once.
StatusOr<Svdag> BuildDagChunked(std::span<const uint64_t> morton, int depth, int chunk_levels,
                                const DagBuildOptions& options = {});

}  // namespace pointdag
