#include "pointdag/gpu/voxel_reduce.h"

#include <algorithm>
#include <cstring>

#include "pointdag/gpu/tiling.h"

#include "shaders/voxel_accumulate.spv.h"
#include "shaders/voxel_finish.spv.h"
#include "shaders/voxel_heads.spv.h"
#include "shaders/voxel_histogram.spv.h"
#include "shaders/voxel_morton.spv.h"
#include "shaders/voxel_scan.spv.h"
#include "shaders/voxel_scan_tiles.spv.h"
#include "shaders/voxel_scatter.spv.h"

namespace pointdag::gpu {
namespace {

constexpr uint32_t kDigits = 256;
constexpr uint32_t kBuffers = 8;

enum KernelId { kHistogram, kScanTiles, kScan, kScatter, kHeads, kAccumulate, kFinish, kKernels };
const KernelSource kSources[kKernels] = {
    {"voxel_histogram", voxel_histogram_spirv}, {"voxel_scan_tiles", voxel_scan_tiles_spirv},
    {"voxel_scan", voxel_scan_spirv},           {"voxel_scatter", voxel_scatter_spirv},
    {"voxel_heads", voxel_heads_spirv},         {"voxel_accumulate", voxel_accumulate_spirv},
    {"voxel_finish", voxel_finish_spirv}};

}  // namespace

StatusOr<std::vector<uint64_t>> MortonCodes(VulkanContext& vulkan, std::span<const std::array<uint32_t, 3>> cells) {
  if (cells.empty()) return std::vector<uint64_t>{};
  if (cells.size() > 0xFFFFFFFFull) return ResourceLimit("too many cells for one dispatch");
  ASSIGN_OR_RETURN(const Kernel* kernel, vulkan.GetKernel("voxel_morton", voxel_morton_spirv, 2, 4));
  ASSIGN_OR_RETURN(Buffer cell_buffer, vulkan.CreateBuffer(cells.size() * 12));
  ASSIGN_OR_RETURN(Buffer codes, vulkan.CreateBuffer(cells.size() * 8));
  std::memcpy(cell_buffer.data(), cells.data(), cells.size() * 12);
  const std::array<const Buffer*, 2> bound = {&cell_buffer, &codes};
  Dispatch d;
  d.kernel = kernel;
  d.buffers = bound;
  d.push[0] = static_cast<uint32_t>(cells.size());
  const uint64_t groups = (cells.size() + kGroupSize - 1) / kGroupSize;
  d.groups_x = static_cast<uint32_t>(std::min<uint64_t>(groups, 65535));  // rows of x groups, y rows
  d.groups_y = static_cast<uint32_t>((groups + d.groups_x - 1) / d.groups_x);
  RETURN_IF_ERROR(vulkan.Run(std::span<const Dispatch>(&d, 1)));
  const auto* out = static_cast<const uint64_t*>(codes.data());
  return std::vector<uint64_t>(out, out + cells.size());
}

StatusOr<DeviceVoxels> ReduceVoxels(VulkanContext& vulkan, std::span<const uint64_t> keys,
                                    std::span<const std::array<uint16_t, 3>> rgb, int key_bits, uint32_t divisor) {
  const size_t count = keys.size();
  if (count == 0) return DeviceVoxels{};
  if (!rgb.empty() && rgb.size() != count) return InvalidArgument("one color per point, or none");
  // voxel_scan walks one entry per tile in one invocation: keep it under lavapipe's loop limit.
  if (count > size_t{kMaxTiles} * kTile) return ResourceLimit("too many points for one reduction on the device (lower --chunk-points)");
  std::array<const Kernel*, kKernels> kernels;
  for (int k = 0; k < kKernels; ++k) {
    ASSIGN_OR_RETURN(kernels[k], vulkan.GetKernel(kSources[k].name, kSources[k].spirv, kBuffers, 16));
  }
  const uint32_t n = static_cast<uint32_t>(count);
  const uint32_t tiles = (n + kTile - 1) / kTile;
  ASSIGN_OR_RETURN(Buffer keys_a, vulkan.CreateBuffer(count * 8));
  ASSIGN_OR_RETURN(Buffer points_a, vulkan.CreateBuffer(count * 4));
  ASSIGN_OR_RETURN(Buffer keys_b, vulkan.CreateBuffer(count * 8));
  ASSIGN_OR_RETURN(Buffer points_b, vulkan.CreateBuffer(count * 4));
  ASSIGN_OR_RETURN(Buffer counts, vulkan.CreateBuffer((size_t{kDigits} * tiles + kDigits + 1) * 4));
  ASSIGN_OR_RETURN(Buffer colors, vulkan.CreateBuffer(count * 8));
  ASSIGN_OR_RETURN(Buffer sums, vulkan.CreateBuffer(count * 7 * 4));
  ASSIGN_OR_RETURN(Buffer voxels, vulkan.CreateBuffer(count * 16));
  std::memcpy(keys_a.data(), keys.data(), count * 8);  // little-endian: low word first, as uvec2
  auto* points = static_cast<uint32_t*>(points_a.data());
  auto* packed = static_cast<uint32_t*>(colors.data());
  for (uint32_t i = 0; i < n; ++i) {
    points[i] = i;
    const auto c = rgb.empty() ? std::array<uint16_t, 3>{0, 0, 0} : rgb[i];
    packed[2 * i] = c[0] | uint32_t{c[1]} << 16;
    packed[2 * i + 1] = c[2];
  }
  std::memset(sums.data(), 0, sums.size());

  const std::array<const Buffer*, kBuffers> forward = {&keys_a, &points_a, &keys_b, &points_b, &counts, &colors, &sums, &voxels};
  const std::array<const Buffer*, kBuffers> backward = {&keys_b, &points_b, &keys_a, &points_a, &counts, &colors, &sums, &voxels};
  const uint32_t per_tile = (tiles + kGroupSize - 1) / kGroupSize;
  const auto make = [&](KernelId kernel, const std::array<const Buffer*, kBuffers>& bound, uint32_t shift, uint32_t extra,
                        uint32_t groups) {
    Dispatch d;
    d.kernel = kernels[kernel];
    d.buffers = bound;
    d.push = {n, tiles, shift, extra};
    d.groups_x = groups;
    return d;
  };
  std::vector<Dispatch> dispatches;
  const int passes = (std::max(key_bits, 1) + 7) / 8;
  for (int pass = 0; pass < passes; ++pass) {
    const auto& bound = pass % 2 == 0 ? forward : backward;
    const uint32_t shift = 8 * static_cast<uint32_t>(pass);
    dispatches.push_back(make(kHistogram, bound, shift, 0, per_tile));
    dispatches.push_back(make(kScanTiles, bound, shift, 0, kDigits / kGroupSize));
    dispatches.push_back(make(kScan, bound, kDigits * tiles, kDigits, 1));
    dispatches.push_back(make(kScatter, bound, shift, 0, per_tile));
  }
  // The sorted keys are the last pass's destination: bind them as the source.
  const auto& sorted = passes % 2 == 0 ? forward : backward;
  dispatches.push_back(make(kHeads, sorted, 0, divisor, per_tile));
  dispatches.push_back(make(kScan, sorted, 0, tiles, 1));
  dispatches.push_back(make(kAccumulate, sorted, 0, divisor, per_tile));
  dispatches.push_back(make(kFinish, sorted, 0, divisor, per_tile));
  RETURN_IF_ERROR(vulkan.Run(dispatches));

  const uint32_t total = static_cast<const uint32_t*>(counts.data())[tiles];
  if (total == 0 || total > n) return Internal("the voxel kernels reported " + std::to_string(total) + " voxels");
  DeviceVoxels out;
  out.morton.resize(total);
  if (!rgb.empty()) out.colors.resize(total);
  const auto* entries = static_cast<const std::array<uint32_t, 4>*>(voxels.data());
  for (uint32_t v = 0; v < total; ++v) {
    out.morton[v] = entries[v][0] | uint64_t{entries[v][1]} << 32;
    if (!rgb.empty()) {
      out.colors[v] = {static_cast<uint8_t>(entries[v][2]), static_cast<uint8_t>(entries[v][2] >> 8), static_cast<uint8_t>(entries[v][2] >> 16)};
    }
  }
  return out;
}

}  // namespace pointdag::gpu
