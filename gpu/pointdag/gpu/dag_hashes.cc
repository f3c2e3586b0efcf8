#include "pointdag/gpu/dag_hashes.h"

#include <cstring>

#include "pointdag/gpu/tiling.h"

#include "shaders/dag_hash.spv.h"
#include "shaders/dag_heads.spv.h"
#include "shaders/dag_starts.spv.h"
#include "shaders/voxel_scan.spv.h"

namespace pointdag::gpu {
namespace {

constexpr uint32_t kBuffers = 6;

}  // namespace

StatusOr<DagLevelHashes> HashDagLevels(VulkanContext& vulkan, std::span<const uint64_t> morton, int depth) {
  if (morton.empty()) return InvalidArgument("a DAG needs at least one voxel");
  // voxel_scan walks one entry per tile in one invocation: keep it under lavapipe's loop limit.
  if (morton.size() > size_t{kMaxTiles} * kTile) return ResourceLimit("too many voxels to hash on the device in one piece");
  ASSIGN_OR_RETURN(const Kernel* heads, vulkan.GetKernel("dag_heads", dag_heads_spirv, kBuffers, 16));
  // voxel_scan touches only binding 4, where the DAG kernels keep their counts too.
  ASSIGN_OR_RETURN(const Kernel* scan, vulkan.GetKernel("dag_scan", voxel_scan_spirv, kBuffers, 16));
  ASSIGN_OR_RETURN(const Kernel* starts, vulkan.GetKernel("dag_starts", dag_starts_spirv, kBuffers, 16));
  ASSIGN_OR_RETURN(const Kernel* hash, vulkan.GetKernel("dag_hash", dag_hash_spirv, kBuffers, 16));

  DagLevelHashes out;
  out.hashes.resize(static_cast<size_t>(depth) + 1);
  ASSIGN_OR_RETURN(Buffer below_keys, vulkan.CreateBuffer(morton.size() * 8));
  ASSIGN_OR_RETURN(Buffer below_hashes, vulkan.CreateBuffer(8));  // the bricks read no hashes below
  std::memcpy(below_keys.data(), morton.data(), morton.size() * 8);
  uint32_t count = static_cast<uint32_t>(morton.size());
  for (int height = 2; height <= depth; ++height) {
    const uint32_t tiles = (count + kTile - 1) / kTile, groups = (tiles + kGroupSize - 1) / kGroupSize;
    ASSIGN_OR_RETURN(Buffer firsts, vulkan.CreateBuffer(size_t{count} * 4));
    ASSIGN_OR_RETURN(Buffer keys, vulkan.CreateBuffer(size_t{count} * 8));
    ASSIGN_OR_RETURN(Buffer counts, vulkan.CreateBuffer((size_t{tiles} + 1) * 4));
    ASSIGN_OR_RETURN(Buffer hashes, vulkan.CreateBuffer(size_t{count} * 8));
    const std::array<const Buffer*, kBuffers> bound = {&below_keys, &below_hashes, &firsts, &keys, &counts, &hashes};
    const uint32_t shift = height == 2 ? 6 : 3;
    const uint32_t cells_per_invocation = kTile >> shift;  // as dag_hash.comp
    const uint32_t hash_groups = ((count + cells_per_invocation - 1) / cells_per_invocation + kGroupSize - 1) / kGroupSize;
    const auto make = [&](const Kernel* kernel, std::array<uint32_t, 4> push, uint32_t x) {
      Dispatch d;
      d.kernel = kernel;
      d.buffers = bound;
      std::copy(push.begin(), push.end(), d.push.begin());
      d.groups_x = x;
      return d;
    };
    const std::array<Dispatch, 4> dispatches = {make(heads, {count, tiles, shift, 0}, groups), make(scan, {count, tiles, 0, tiles}, 1),
                                                make(starts, {count, tiles, shift, 0}, groups), make(hash, {count, tiles, shift, 0}, hash_groups)};
    RETURN_IF_ERROR(vulkan.Run(dispatches));
    const uint32_t cells = static_cast<const uint32_t*>(counts.data())[tiles];
    if (cells == 0 || cells > count) return Internal("the DAG kernels reported " + std::to_string(cells) + " cells");
    const auto* level = static_cast<const uint64_t*>(hashes.data());
    out.hashes[height].assign(level, level + cells);
    if (height == depth && cells != 1) return InvalidArgument("Morton code outside the depth-" + std::to_string(depth) + " grid");
    count = cells;
    below_keys = std::move(keys);
    below_hashes = std::move(hashes);
  }
  return out;
}

}  // namespace pointdag::gpu
