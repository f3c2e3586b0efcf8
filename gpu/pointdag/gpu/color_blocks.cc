#include "pointdag/gpu/color_blocks.h"

#include <array>

#include "shaders/block_encode.spv.h"

namespace pointdag::gpu {
namespace {

constexpr uint32_t kMacroBlockColors = 16384;  // as codec/pointdag/color/block_codec.h
constexpr uint32_t kLevels = 5;

struct Params {
  uint32_t count, fixed_rate, threshold_lo, threshold_hi;
};

}  // namespace

StatusOr<std::vector<DeviceColorBlock>> EncodeColorBlocks(VulkanContext& vulkan, std::span<const uint8_t> rgb,
                                                          bool fixed_rate, uint64_t threshold_scaled) {
  const size_t count = rgb.size() / 3;
  if (count == 0) return std::vector<DeviceColorBlock>{};
  if (count > 0xFFFFFFFFull) return ResourceLimit("too many colors for one dispatch");
  const size_t macros = (count + kMacroBlockColors - 1) / kMacroBlockColors;
  ASSIGN_OR_RETURN(const Kernel* kernel, vulkan.GetKernel("block_encode", block_encode_spirv, 6, sizeof(Params)));
  ASSIGN_OR_RETURN(Buffer colors, vulkan.CreateBuffer(count * 4));
  ASSIGN_OR_RETURN(Buffer prefix, vulkan.CreateBuffer(macros * (kMacroBlockColors + 1) * 9 * 4));
  ASSIGN_OR_RETURN(Buffer levels, vulkan.CreateBuffer(macros * kLevels * kMacroBlockColors * 16));
  ASSIGN_OR_RETURN(Buffer costs, vulkan.CreateBuffer(macros * kLevels * kMacroBlockColors * 4));
  ASSIGN_OR_RETURN(Buffer blocks, vulkan.CreateBuffer(macros * kMacroBlockColors * 16));
  ASSIGN_OR_RETURN(Buffer counts, vulkan.CreateBuffer(macros * 4));
  auto* packed = static_cast<uint32_t*>(colors.data());
  for (size_t i = 0; i < count; ++i) packed[i] = rgb[3 * i] | uint32_t{rgb[3 * i + 1]} << 8 | uint32_t{rgb[3 * i + 2]} << 16;
  const Params params{static_cast<uint32_t>(count), fixed_rate ? 1u : 0u, static_cast<uint32_t>(threshold_scaled),
                      static_cast<uint32_t>(threshold_scaled >> 32)};
  const std::array<const Buffer*, 6> bound = {&colors, &prefix, &levels, &costs, &blocks, &counts};
  RETURN_IF_ERROR(vulkan.Run(*kernel, bound, &params, static_cast<uint32_t>(macros)));

  std::vector<DeviceColorBlock> out;
  const auto* per_macro = static_cast<const uint32_t*>(counts.data());
  const auto* entries = static_cast<const std::array<uint32_t, 4>*>(blocks.data());
  for (size_t m = 0; m < macros; ++m) {
    if (per_macro[m] > kMacroBlockColors) return Internal("the block encoder kernel reported " + std::to_string(per_macro[m]) + " blocks in a macro block");
    for (uint32_t k = 0; k < per_macro[m]; ++k) {
      const auto& e = entries[m * kMacroBlockColors + k];
      DeviceColorBlock b;
      b.start = e[0];
      b.length = e[1];
      b.bits = static_cast<uint8_t>(e[2] >> 24);
      for (int c = 0; c < 3; ++c) {
        b.a[c] = static_cast<uint8_t>(e[2] >> (8 * c));
        b.b[c] = static_cast<uint8_t>(e[3] >> (8 * c));
      }
      out.push_back(b);
    }
  }
  return out;
}

}  // namespace pointdag::gpu
