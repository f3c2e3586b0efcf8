// Stage 3 on Vulkan: Morton codes of integer cells (gpu/shaders/voxel_morton.comp), and points
// keyed by Morton code -> one voxel per distinct code with the mean of its
// points' colors, as the CPU's ReduceChunk (codec/pointdag/voxelize/voxelizer.cc) and with the same
// result: an LSD radix sort of the codes (8 bits a pass, as many passes as `key_bits` needs), then
// voxel starts counted per tile, colors summed per voxel and averaged (gpu/shaders/voxel_*.comp).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/gpu/vulkan_context.h"
#include "pointdag/status.h"

namespace pointdag::gpu {

struct DeviceVoxels {
  std::vector<uint64_t> morton;                // sorted, unique
  std::vector<std::array<uint8_t, 3>> colors;  // parallel to morton; empty without input colors
};

// `keys`: one Morton code per point, below 2^key_bits. `rgb`: one color per point, or empty.
// `divisor`: 1 for 8-bit colors, 257 for 16-bit ones (the mean is rounded half up, then divided).
// One Morton code per cell (x, y, z below 2^21), as MortonEncode in codec/pointdag/voxelize/morton.h.
StatusOr<std::vector<uint64_t>> MortonCodes(VulkanContext& vulkan, std::span<const std::array<uint32_t, 3>> cells);

StatusOr<DeviceVoxels> ReduceVoxels(VulkanContext& vulkan, std::span<const uint64_t> keys,
                                    std::span<const std::array<uint16_t, 3>> rgb, int key_bits, uint32_t divisor);

}  // namespace pointdag::gpu
