// Stage 5b on Vulkan: the block color encoder of codec/pointdag/color/block_codec.h as a sequence of
// small kernels (gpu/shaders/block_*.comp): prefix sums per macro block, every candidate merge fitted
// by its own invocation, each merge pass and each level of IIB's cut walked per macro block. It
// returns exactly the blocks the CPU encoder returns for the same colors and threshold (gpu_test).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/gpu/vulkan_context.h"
#include "pointdag/status.h"

namespace pointdag::gpu {

struct DeviceColorBlock {
  uint32_t start = 0, length = 0;
  uint8_t bits = 0;
  uint8_t a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
};

// `rgb`: 3 bytes per color. `fixed_rate`: IIA (3 bits everywhere) or IIB. `threshold_scaled`: the
// block codec's integer threshold, floor(3072 * max MSE per channel).
StatusOr<std::vector<DeviceColorBlock>> EncodeColorBlocks(VulkanContext& vulkan, std::span<const uint8_t> rgb,
                                                          bool fixed_rate, uint64_t threshold_scaled);

}  // namespace pointdag::gpu
