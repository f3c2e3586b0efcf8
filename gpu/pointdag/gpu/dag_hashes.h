// Stage 4b on Vulkan: the subtree hash of every cell of every octree level, bricks (height 2) up to
// the root, from sorted unique Morton codes (gpu/shaders/dag_*.comp). They equal the hashes the
// CPU builder (codec/pointdag/dag/dag_builder.cc) computes with XXH3-64, so it can intern with
// them instead: the DAG comes out the same.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/gpu/vulkan_context.h"
#include "pointdag/status.h"

namespace pointdag::gpu {

// hashes[h] for height h = 2..depth: one per occupied cell of that height, in Morton order
// (hashes[0] and hashes[1] are empty).
struct DagLevelHashes {
  std::vector<std::vector<uint64_t>> hashes;
};

StatusOr<DagLevelHashes> HashDagLevels(VulkanContext& vulkan, std::span<const uint64_t> morton, int depth);

}  // namespace pointdag::gpu
