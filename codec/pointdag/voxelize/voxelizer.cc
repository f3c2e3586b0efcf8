#include "pointdag/voxelize/voxelizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "pointdag/gpu/stage_device.h"
#include "pointdag/gpu/voxel_reduce.h"
#include "pointdag/voxelize/morton.h"
#include "pointdag/voxelize/radix_sort.h"

namespace pointdag {
namespace {

struct KeyedPoint {
  uint64_t key;
  std::array<uint16_t, 3> rgb;
};

StatusOr<gpu::StageTiming> CalibrateVoxelize(gpu::VulkanContext& device);

}  // namespace

std::array<double, 3> VoxelGrid::VoxelCentre(uint64_t code) const {
  const auto cell = MortonDecode(code);
  return {origin[0] + (cell[0] + 0.5) * voxel_size, origin[1] + (cell[1] + 0.5) * voxel_size,
          origin[2] + (cell[2] + 0.5) * voxel_size};
}

StatusOr<gpu::VulkanContext*> VoxelizeDevice() { return gpu::DeviceFor(gpu::Stage::kVoxelize, CalibrateVoxelize); }

StatusOr<int> DepthForVoxelSize(double extent, double voxel_size) {
  if (!std::isfinite(voxel_size) || voxel_size <= 0) {
    return InvalidArgument("voxel size must be a positive finite number");
  }
  const double cells = std::floor(extent / voxel_size) + 1;  // the maximum point needs a cell too
  int depth = 2;
  while (depth <= kMaxDepth && std::ldexp(1.0, depth) < cells) ++depth;
  if (depth > kMaxDepth) {
    return InvalidArgument("voxel size " + std::to_string(voxel_size) + " is too small for an extent of " +
                           std::to_string(extent) + ": the grid would need more than 2^21 voxels per side");
  }
  return depth;
}

namespace {

// The rounded mean of `points` values summing to `sum`, in 8 bits: half up, exactly (integers, as
// the Vulkan kernel does); `divisor` 257 scales 16-bit sources.
uint8_t MeanChannel(uint64_t sum, uint64_t points, uint64_t divisor) {
  const uint64_t d = points * divisor;
  return static_cast<uint8_t>(std::min<uint64_t>((2 * sum + d) / (2 * d), 255));
}

void ReduceOnCpu(std::vector<KeyedPoint>& points, const ScanSurvey& survey, int key_bits, VoxelGrid& grid) {
  // In place (its scratch is bounded): a scratch copy would double the peak memory of the whole
  // pipeline. The order among a voxel's points does not matter (integer sums), so any sort gives
  // the same voxels.
  RadixSortInPlace(std::span(points), key_bits, [](const KeyedPoint& p) { return p.key; });
  size_t voxels = points.empty() ? 0 : 1;
  for (size_t i = 1; i < points.size(); ++i) voxels += points[i].key != points[i - 1].key;
  // Room for this chunk's voxels at once, growing geometrically across chunks as push_back would.
  const auto make_room = [voxels](auto& v) {
    if (v.capacity() < v.size() + voxels) v.reserve(std::max(v.size() + voxels, 2 * v.capacity()));
  };
  make_room(grid.morton);
  if (survey.has_color) make_room(grid.colors);
  const uint64_t divisor = survey.color_bits > 8 ? 257 : 1;
  for (size_t begin = 0; begin < points.size();) {
    size_t end = begin + 1;
    while (end < points.size() && points[end].key == points[begin].key) ++end;
    grid.morton.push_back(points[begin].key);
    if (survey.has_color && end - begin == 1 && divisor == 1) {
      const auto& rgb = points[begin].rgb;  // the mean of one 8-bit value is itself
      grid.colors.push_back({static_cast<uint8_t>(rgb[0]), static_cast<uint8_t>(rgb[1]), static_cast<uint8_t>(rgb[2])});
    } else if (survey.has_color) {
      uint64_t sum[3] = {0, 0, 0};
      for (size_t i = begin; i < end; ++i) {
        for (int ch = 0; ch < 3; ++ch) sum[ch] += points[i].rgb[ch];
      }
      grid.colors.push_back({MeanChannel(sum[0], end - begin, divisor), MeanChannel(sum[1], end - begin, divisor),
                             MeanChannel(sum[2], end - begin, divisor)});
    }
    begin = end;
  }
}

// The same voxels from the Vulkan kernels (gpu/shaders/voxel_*.comp).
Status ReduceOnDevice(gpu::VulkanContext& device, const std::vector<KeyedPoint>& points, const ScanSurvey& survey,
                      int key_bits, VoxelGrid& grid) {
  std::vector<uint64_t> keys(points.size());
  std::vector<std::array<uint16_t, 3>> rgb(survey.has_color ? points.size() : 0);
  for (size_t i = 0; i < points.size(); ++i) {
    keys[i] = points[i].key;
    if (survey.has_color) rgb[i] = points[i].rgb;
  }
  ASSIGN_OR_RETURN(const gpu::DeviceVoxels voxels, gpu::ReduceVoxels(device, keys, rgb, key_bits, survey.color_bits > 8 ? 257 : 1));
  grid.morton.insert(grid.morton.end(), voxels.morton.begin(), voxels.morton.end());
  for (const auto& c : voxels.colors) grid.colors.push_back({c[0], c[1], c[2]});
  return Status::Ok();
}

// Both paths on 2^18 points in 2^15 voxels of a depth-10 grid (Vulkan after a warm-up run).
StatusOr<gpu::StageTiming> CalibrateVoxelize(gpu::VulkanContext& device) {
  std::vector<KeyedPoint> points(1 << 18);
  uint32_t state = 987654321;
  for (KeyedPoint& p : points) {
    state = state * 1664525u + 1013904223u;
    p.key = MortonEncode((state >> 17) & 31, (state >> 22) & 31, (state >> 27) & 31) << 15 | (state & 0x7FFF);
    p.rgb = {static_cast<uint16_t>(state >> 8 & 255), static_cast<uint16_t>(state >> 16 & 255), static_cast<uint16_t>(state >> 24)};
  }
  ScanSurvey survey;
  survey.has_color = true;
  survey.color_bits = 8;
  using Clock = std::chrono::steady_clock;
  const auto seconds = [](Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); };
  gpu::StageTiming timing;
  VoxelGrid grid;
  RETURN_IF_ERROR(ReduceOnDevice(device, points, survey, 30, grid));
  grid = {};
  auto start = Clock::now();
  RETURN_IF_ERROR(ReduceOnDevice(device, points, survey, 30, grid));
  timing.vulkan_seconds = seconds(start);
  grid = {};
  start = Clock::now();
  ReduceOnCpu(points, survey, 30, grid);
  timing.cpu_seconds = seconds(start);
  return timing;
}

// Points of one chunk -> voxels appended to the grid (mean colors), then the chunk callback.
Status ReduceChunk(std::vector<KeyedPoint>& points, const ScanSurvey& survey, VoxelGrid& grid, const ChunkFn& on_chunk) {
  const size_t first_voxel = grid.morton.size();
  ASSIGN_OR_RETURN(gpu::VulkanContext* const device, VoxelizeDevice());
  if (device) {
    RETURN_IF_ERROR(ReduceOnDevice(*device, points, survey, 3 * grid.depth, grid));
  } else {
    ReduceOnCpu(points, survey, 3 * grid.depth, grid);
  }
  std::vector<KeyedPoint>().swap(points);  // give the points back before the chunk's DAG is built
  return on_chunk ? on_chunk(grid, first_voxel) : Status::Ok();
}

// Chunk files of one voxelization, removed with their folder however the voxelization ends.
class SpillFiles {
 public:
  Status Create(const std::filesystem::path& parent, size_t chunks) {
    std::error_code ec;
    const auto base = parent.empty() ? std::filesystem::temp_directory_path(ec) : parent;
    std::string dir = (base / "pointdag-spill-XXXXXX").string();
    if (ec || !mkdtemp(dir.data())) return IoError("cannot create a spill folder in " + base.string());
    dir_ = dir;
    files_.assign(chunks, nullptr);
    return Status::Ok();
  }
  ~SpillFiles() {
    for (std::FILE* f : files_) {
      if (f) std::fclose(f);
    }
    std::error_code ec;
    if (!dir_.empty()) std::filesystem::remove_all(dir_, ec);
  }
  Status Append(size_t chunk, const KeyedPoint& p) {
    if (!files_[chunk]) {
      files_[chunk] = std::fopen((dir_ / std::to_string(chunk)).c_str(), "w+b");
      if (!files_[chunk]) return IoError("cannot create a spill file in " + dir_.string());
    }
    if (std::fwrite(&p, sizeof(p), 1, files_[chunk]) != 1) return IoError("cannot write a spill file (disk full?)");
    return Status::Ok();
  }
  // Reads a chunk's points back and deletes its file; empty for a chunk that got no point.
  Status Take(size_t chunk, std::vector<KeyedPoint>& points) {
    points.clear();
    std::FILE* f = files_[chunk];
    if (!f) return Status::Ok();
    const long bytes = std::ftell(f);
    points.resize(static_cast<size_t>(bytes) / sizeof(KeyedPoint));
    std::rewind(f);
    const bool ok = std::fread(points.data(), sizeof(KeyedPoint), points.size(), f) == points.size();
    std::fclose(f);
    files_[chunk] = nullptr;
    std::filesystem::remove(dir_ / std::to_string(chunk));
    return ok ? Status::Ok() : IoError("cannot read back a spill file");
  }

 private:
  std::filesystem::path dir_;
  std::vector<std::FILE*> files_;
};

int ChunkLevels(uint64_t points, uint64_t max_in_memory, int depth) {
  int k = 0;
  while (k < std::min(3, depth - 2) && points > (max_in_memory << (3 * k))) ++k;
  return k;
}

}  // namespace

StatusOr<VoxelGrid> Voxelize(ScanReader& reader, const VoxelizeOptions& options) {
  if (int{options.voxel_size.has_value()} + int{options.depth.has_value()} + int{bool(options.voxel_size_after_survey)} != 1) {
    return InvalidArgument("give exactly one of voxel size and depth");
  }
  ASSIGN_OR_RETURN(ScanSurvey survey, SurveyScan(reader, options.batch_points));
  std::optional<double> voxel_size = options.voxel_size;
  if (options.voxel_size_after_survey) {
    ASSIGN_OR_RETURN(voxel_size, options.voxel_size_after_survey());
  }

  VoxelGrid grid;
  grid.origin = survey.bounds.min;
  grid.points_in = survey.points;
  grid.source_color_bits = survey.color_bits;
  double extent = 0;
  for (int axis = 0; axis < 3; ++axis) extent = std::max(extent, survey.bounds.max[axis] - survey.bounds.min[axis]);

  if (options.depth) {
    if (*options.depth < 2 || *options.depth > kMaxDepth) {
      return InvalidArgument("depth must be between 2 and 21, got " + std::to_string(*options.depth));
    }
    grid.depth = *options.depth;
    grid.voxel_size = extent > 0 ? extent / std::ldexp(1.0, grid.depth) : 1.0;
  } else {
    ASSIGN_OR_RETURN(grid.depth, DepthForVoxelSize(extent, *voxel_size));
    grid.voxel_size = *voxel_size;
  }
  grid.chunk_levels = ChunkLevels(survey.points, std::max<uint64_t>(1, options.max_points_in_memory), grid.depth);
  const int chunk_shift = 3 * (grid.depth - grid.chunk_levels);

  SpillFiles spill;
  std::vector<KeyedPoint> points;
  if (grid.chunk_levels > 0) {
    RETURN_IF_ERROR(spill.Create(options.spill_dir, size_t{1} << (3 * grid.chunk_levels)));
  } else {
    points.reserve(static_cast<size_t>(survey.points));
  }
  const double max_cell = static_cast<double>((uint32_t{1} << grid.depth) - 1);
  const double inv_size = 1.0 / grid.voxel_size;
  ASSIGN_OR_RETURN(gpu::VulkanContext* const device, VoxelizeDevice());
  uint64_t read = 0;
  PointBatch batch;
  std::vector<std::array<uint32_t, 3>> cells;
  std::vector<uint64_t> codes;
  const auto cell_of = [&](const std::array<double, 3>& xyz) {
    std::array<uint32_t, 3> cell;
    for (int axis = 0; axis < 3; ++axis) {
      // The cast truncates, which is the floor on [0, max_cell], and the clamp sends the rest to
      // the ends as the floor did (std::floor without SSE4.1 is a dozen instructions per axis).
      const double c = (xyz[axis] - grid.origin[axis]) * inv_size;
      cell[axis] = static_cast<uint32_t>(std::clamp(c, 0.0, max_cell));
    }
    return cell;
  };
  for (;;) {
    ASSIGN_OR_RETURN(size_t n, reader.Read(batch, options.batch_points));
    if (n == 0) break;
    if (device) {
      cells.resize(n);
      for (size_t i = 0; i < n; ++i) cells[i] = cell_of(batch.xyz[i]);
      ASSIGN_OR_RETURN(codes, gpu::MortonCodes(*device, cells));
    } else {
      codes.resize(n);
      for (size_t i = 0; i < n; ++i) {
        const std::array<uint32_t, 3> cell = cell_of(batch.xyz[i]);
        codes[i] = MortonEncode(cell[0], cell[1], cell[2]);
      }
    }
    const auto point = [&](size_t i) {
      return KeyedPoint{codes[i], survey.has_color ? batch.rgb[i] : std::array<uint16_t, 3>{0, 0, 0}};
    };
    if (grid.chunk_levels > 0) {
      for (size_t i = 0; i < n; ++i) RETURN_IF_ERROR(spill.Append(static_cast<size_t>(codes[i] >> chunk_shift), point(i)));
    } else {
      for (size_t i = 0; i < n; ++i) points.push_back(point(i));
    }
    read += n;
    if (options.progress) options.progress(read, survey.points);
  }
  if (read != survey.points) {
    return Internal("scan yielded " + std::to_string(read) + " points on its second pass, " +
                    std::to_string(survey.points) + " on its first");
  }
  if (grid.chunk_levels == 0) {
    RETURN_IF_ERROR(ReduceChunk(points, survey, grid, options.on_chunk));
    return grid;
  }
  for (size_t chunk = 0; chunk < (size_t{1} << (3 * grid.chunk_levels)); ++chunk) {
    RETURN_IF_ERROR(spill.Take(chunk, points));
    if (!points.empty()) RETURN_IF_ERROR(ReduceChunk(points, survey, grid, options.on_chunk));
  }
  return grid;
}

}  // namespace pointdag
