#include "pointdag/gpu/color_blocks.h"

#include <array>
#include <cstring>

#include "pointdag/gpu/tiling.h"

#include "shaders/block_cut.spv.h"
#include "shaders/block_emit.spv.h"
#include "shaders/block_merge.spv.h"
#include "shaders/block_open.spv.h"
#include "shaders/block_pairs.spv.h"
#include "shaders/block_refit.spv.h"
#include "shaders/block_start.spv.h"

namespace pointdag::gpu {
namespace {

constexpr uint32_t kMacroBlockColors = 16384;  // as codec/pointdag/color/block_codec.h
constexpr uint32_t kLevels = 5;
constexpr uint32_t kFirstMergedBits = 2;  // as block_codec.cc: the levels below keep the leaves
constexpr uint32_t kPassesPerSubmit = 4;       // merge passes recorded per submission
constexpr uint32_t kFixedRateBits = 3;

// block_common.glsl's Params, word for word.
enum Param { kCount, kMacros, kLevel, kBits, kThresholdLo, kThresholdHi, kFixedRate, kSlot, kParams };
static_assert(kParams == Dispatch::kMaxPushWords);

enum KernelId { kStart, kRefit, kPairs, kMerge, kCut, kOpen, kEmit, kKernels };
const KernelSource kSources[kKernels] = {
    {"block_start", block_start_spirv}, {"block_refit", block_refit_spirv}, {"block_pairs", block_pairs_spirv},
    {"block_merge", block_merge_spirv}, {"block_cut", block_cut_spirv},     {"block_open", block_open_spirv},
    {"block_emit", block_emit_spirv}};

enum BufferId { kColors, kPrefix, kLevelsBuffer, kPairsBuffer, kCosts, kCounts, kBlocks, kMerges, kBuffers };

// Records the dispatches of one encoding: the kernels, their shared buffers and parameters.
class Encoder {
 public:
  Encoder(std::array<const Kernel*, kKernels> kernels, const std::array<const Buffer*, kBuffers>& buffers,
          std::array<uint32_t, kParams> params)
      : kernels_(kernels), buffers_(buffers), params_(params) {}

  // One invocation per macro block.
  Dispatch PerMacro(KernelId kernel, uint32_t level, uint32_t slot = 0) const {
    return Make(kernel, level, slot, (params_[kMacros] + kGroupSize - 1) / kGroupSize, 1);
  }
  // One invocation per block slot: x within the macro block, y the macro block.
  Dispatch PerBlock(KernelId kernel, uint32_t level, uint32_t bits) const {
    Dispatch d = Make(kernel, level, 0, kMacroBlockColors / kGroupSize, params_[kMacros]);
    d.push[kBits] = bits;
    return d;
  }

 private:
  Dispatch Make(KernelId kernel, uint32_t level, uint32_t slot, uint32_t x, uint32_t y) const {
    Dispatch d;
    d.kernel = kernels_[kernel];
    d.buffers = buffers_;
    d.push = params_;
    d.push[kLevel] = level;
    d.push[kSlot] = slot;
    d.groups_x = x;
    d.groups_y = y;
    return d;
  }
  std::array<const Kernel*, kKernels> kernels_;
  std::span<const Buffer* const> buffers_;
  std::array<uint32_t, kParams> params_;
};

// Merge passes over one level until one merges nothing, kPassesPerSubmit per submission (a pass
// after one that merged nothing changes nothing: every pair left is a known failure). `first`:
// dispatches that go before the first pass.
Status MergeLevel(VulkanContext& vulkan, const Encoder& encoder, Buffer& merges, uint32_t level, uint32_t bits,
                  std::vector<Dispatch> first) {
  for (std::vector<Dispatch> batch = std::move(first);; batch.clear()) {
    for (uint32_t slot = 0; slot < kPassesPerSubmit; ++slot) {
      batch.push_back(encoder.PerBlock(kPairs, level, bits));
      batch.push_back(encoder.PerMacro(kMerge, level, slot));
    }
    std::memset(merges.data(), 0, merges.size());
    RETURN_IF_ERROR(vulkan.Run(batch));
    if (static_cast<const uint32_t*>(merges.data())[kPassesPerSubmit - 1] == 0) return Status::Ok();
  }
}

}  // namespace

StatusOr<std::vector<DeviceColorBlock>> EncodeColorBlocks(VulkanContext& vulkan, std::span<const uint8_t> rgb,
                                                          bool fixed_rate, uint64_t threshold_scaled) {
  const size_t count = rgb.size() / 3;
  if (count == 0) return std::vector<DeviceColorBlock>{};
  const size_t macros = (count + kMacroBlockColors - 1) / kMacroBlockColors;
  if (macros > 65535) return ResourceLimit("too many colors for one dispatch (at most 65535 macro blocks)");
  std::array<const Kernel*, kKernels> kernels;
  for (int k = 0; k < kKernels; ++k) {
    ASSIGN_OR_RETURN(kernels[k], vulkan.GetKernel(kSources[k].name, kSources[k].spirv, kBuffers, kParams * 4));
  }
  const size_t slots = macros * kMacroBlockColors;
  ASSIGN_OR_RETURN(Buffer colors, vulkan.CreateBuffer(count * 4));
  ASSIGN_OR_RETURN(Buffer prefix, vulkan.CreateBuffer(macros * (kMacroBlockColors + 1) * 9 * 4));
  ASSIGN_OR_RETURN(Buffer levels, vulkan.CreateBuffer(slots * kLevels * 16));
  ASSIGN_OR_RETURN(Buffer pairs, vulkan.CreateBuffer(slots * 16));
  ASSIGN_OR_RETURN(Buffer costs, vulkan.CreateBuffer(slots * kLevels * 8));
  ASSIGN_OR_RETURN(Buffer counts, vulkan.CreateBuffer(macros * kLevels * 4));
  ASSIGN_OR_RETURN(Buffer blocks, vulkan.CreateBuffer((slots + macros) * 16));
  ASSIGN_OR_RETURN(Buffer merges, vulkan.CreateBuffer(kPassesPerSubmit * 4));
  auto* packed = static_cast<uint32_t*>(colors.data());
  for (size_t i = 0; i < count; ++i) packed[i] = rgb[3 * i] | uint32_t{rgb[3 * i + 1]} << 8 | uint32_t{rgb[3 * i + 2]} << 16;

  const std::array<const Buffer*, kBuffers> bound = {&colors, &prefix, &levels, &pairs, &costs, &counts, &blocks, &merges};
  const Encoder encoder(kernels, bound,
                        {static_cast<uint32_t>(count), static_cast<uint32_t>(macros), 0, 0, static_cast<uint32_t>(threshold_scaled),
                         static_cast<uint32_t>(threshold_scaled >> 32), fixed_rate ? 1u : 0u, 0});
  // Level 0: singletons merged at 0 bits (IIB's leaves), or at 3 bits (IIA's blocks).
  RETURN_IF_ERROR(MergeLevel(vulkan, encoder, merges, 0, fixed_rate ? kFixedRateBits : 0, {encoder.PerMacro(kStart, 0)}));
  std::vector<Dispatch> finish;
  if (!fixed_rate) {
    for (uint32_t level = 1; level < kLevels; ++level) {
      if (level < kFirstMergedBits) {
        RETURN_IF_ERROR(vulkan.Run(std::vector<Dispatch>{encoder.PerBlock(kRefit, level, level)}));
      } else {
        RETURN_IF_ERROR(MergeLevel(vulkan, encoder, merges, level, level, {encoder.PerBlock(kRefit, level, level)}));
      }
    }
    for (uint32_t level = 0; level < kLevels; ++level) finish.push_back(encoder.PerMacro(kCut, level));
    for (uint32_t level = kLevels - 1; level > 0; --level) finish.push_back(encoder.PerMacro(kOpen, level));
  }
  finish.push_back(encoder.PerMacro(kEmit, 0));
  RETURN_IF_ERROR(vulkan.Run(finish));

  std::vector<DeviceColorBlock> out;
  const auto* entries = static_cast<const std::array<uint32_t, 4>*>(blocks.data());
  uint64_t covered = 0;
  for (size_t m = 0; m < macros; ++m) {
    const uint32_t n = entries[slots + m][0];
    if (n > kMacroBlockColors) return Internal("the block encoder kernel reported " + std::to_string(n) + " blocks in a macro block");
    for (uint32_t k = 0; k < n; ++k) {
      const auto& e = entries[m * kMacroBlockColors + k];
      DeviceColorBlock b;
      b.start = e[0];
      b.length = e[1];
      b.bits = static_cast<uint8_t>(e[2] >> 24);
      for (int c = 0; c < 3; ++c) {
        b.a[c] = static_cast<uint8_t>(e[2] >> (8 * c));
        b.b[c] = static_cast<uint8_t>(e[3] >> (8 * c));
      }
      if (b.start != covered) return Internal("the block encoder kernel's blocks do not tile the colors");
      covered += b.length;
      out.push_back(b);
    }
  }
  if (covered != count) return Internal("the block encoder kernel's blocks do not cover the colors");
  return out;
}

}  // namespace pointdag::gpu
