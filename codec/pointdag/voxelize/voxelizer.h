// Stage 3: quantize a scan onto a cubic grid of 2^depth voxels per side.
//
// Contract: the grid's origin is the scan's exact minimum corner (found by a first pass, never from
// a header) and its side is the largest extent. Given --voxel S, depth is the smallest in [2, 21]
// whose grid covers the extent; given --depth D the voxel size is extent / 2^D. All points of one
// voxel become one voxel whose color is the mean of their colors rounded half up, in 8 bits (16-bit sources
// are scaled, 8-bit values stored in 16-bit fields are kept). Voxels come out sorted by Morton code,
// which is also the DAG's color order.
//
// Memory: up to max_points_in_memory points are sorted in memory (16 bytes each). Larger scans are
// cut into the 8^k cells of level k (k <= 3, the smallest that fits on average): the second pass
// spills each point to its cell's file, then the cells are reduced one at a time in Morton order,
// so the peak is one cell's points plus the voxels (11 bytes each) instead of every point.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <vector>

#include "pointdag/read/scan_reader.h"

namespace pointdag::gpu {
class VulkanContext;
}

namespace pointdag {

struct Rgb8 {
  uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb8&, const Rgb8&) = default;
};

// Called now and then with (points done, points total) for progress display.
using ProgressFn = std::function<void(uint64_t, uint64_t)>;

struct VoxelGrid;

// Told about each finished chunk: its voxels are grid.morton[first_voxel..] (and the same colors).
using ChunkFn = std::function<Status(const VoxelGrid& grid, size_t first_voxel)>;

struct VoxelizeOptions {
  std::optional<double> voxel_size;  // exactly one of voxel_size, depth and voxel_size_after_survey
  std::optional<int> depth;
  // A voxel size still being worked out (from the scan's spacing, beside the survey pass): asked for
  // once the survey pass is done, the first moment it is needed.
  std::function<StatusOr<double>()> voxel_size_after_survey;
  size_t batch_points = 1 << 14;
  uint64_t max_points_in_memory = uint64_t{1} << 25;
  std::filesystem::path spill_dir;  // where chunk files go; empty: the system's temporary folder
  ProgressFn progress;
  ChunkFn on_chunk;
};

struct VoxelGrid {
  int depth = 0;
  std::array<double, 3> origin{0, 0, 0};  // world position of the grid's minimum corner
  double voxel_size = 1.0;
  std::vector<uint64_t> morton;  // sorted, unique
  std::vector<Rgb8> colors;      // parallel to morton; empty when the scan has no color
  uint64_t points_in = 0;
  int source_color_bits = 8;
  int chunk_levels = 0;  // 0: voxelized in memory; k: in the 8^k cells of level k

  bool has_color() const { return !colors.empty(); }
  // Centre of a voxel in source units.
  std::array<double, 3> VoxelCentre(uint64_t code) const;
};

// Chooses the depth for a voxel size over an extent; kInvalidArgument if it needs more than 21 levels.
StatusOr<int> DepthForVoxelSize(double extent, double voxel_size);

StatusOr<VoxelGrid> Voxelize(ScanReader& reader, const VoxelizeOptions& options);

// Where the sort and reduction of points to voxels runs in this process (null: the CPU), per
// gpu/pointdag/gpu/stage_device.h; under POINTDAG_DEVICE=auto decided on the first call by timing both.
StatusOr<gpu::VulkanContext*> VoxelizeDevice();

}  // namespace pointdag
