#include "pointdag/ingest.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "pointdag/read/remembering_reader.h"
#include "pointdag/voxelize/point_spacing.h"

namespace pointdag {
namespace {

// Scans up to 2 M points (60 MB at 30 bytes a point) are read and georeferenced once, not three
// times (spacing sample, survey, voxelizing): on them the fixed costs weigh most.
constexpr uint64_t kRememberedPoints = uint64_t{1} << 21;

// The first points of a scan, for its spacing; the reader is rewound.
StatusOr<PointBatch> SpacingSample(ScanReader& reader) {
  PointBatch batch;
  ASSIGN_OR_RETURN(const size_t n, reader.Read(batch, 1 << 16));
  RETURN_IF_ERROR(reader.Rewind());
  if (n == 0) return InvalidArgument("the scan holds no points");
  return batch;
}

StatusOr<double> VoxelSizeFromSample(const PointBatch& sample) {
  const double spacing = MedianPointSpacing(sample.xyz);
  if (!(spacing > 0)) return InvalidArgument("cannot derive a voxel size: the first points all coincide; pass voxel");
  return RoundUpTo125(spacing);
}

}  // namespace

StatusOr<double> DeriveVoxelSize(ScanReader& reader) {
  ASSIGN_OR_RETURN(const PointBatch sample, SpacingSample(reader));
  return VoxelSizeFromSample(sample);
}

double RoundUpTo125(double spacing) {
  const double decade = std::pow(10.0, std::floor(std::log10(spacing)));
  for (double step : {1.0, 2.0, 5.0, 10.0}) {
    if (step * decade >= spacing * (1 - 1e-9)) return step * decade;
  }
  return 10 * decade;
}

// glibc's defaults return any freed chunk of 128 KiB or more, and a heap top of twice that, to the
// kernel; a running daemon's second ingest of autzen_trim then took 20,000 page faults and 14 % of
// its CPU in the kernel's clear_page. With these: 9,000 faults, task-clock 438-532 -> 420-427 ms for
// `bench --ingest` on autzen (docs/benchmarks.md). Arrays of 32 MiB and more still come from mmap.
void RetainFreedMemory() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
#endif
}

TilingOptions IngestTilingOptions(int tile_depth, std::optional<double> quality_db) {
  TilingOptions tiling;
  tiling.tile_depth = tile_depth;
  tiling.colors.target_psnr_y = quality_db.value_or(38.0);  // vbr, block stream version 6: TilingOptions' own
  return tiling;
}

StatusOr<IngestedScan> IngestScan(const std::filesystem::path& path, const IngestOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto report = [&](std::string_view stage, double fraction) {
    if (options.progress) options.progress(stage, fraction);
  };
  IngestedScan out;
  report("survey", 0);
  ASSIGN_OR_RETURN(FramedReader framed, OpenScanInFrame(path, options.epsg));
  out.frame = std::move(framed.frame);
  framed.reader = std::make_unique<RememberingReader>(std::move(framed.reader),
                                                      std::min(kRememberedPoints, options.max_points_in_memory));
  VoxelizeOptions vopt;
  vopt.voxel_size = options.voxel_size;
  // The spacing's nearest-neighbour search (one core) runs beside the survey pass, which does not
  // need the voxel size; the future's destructor waits for it on every return.
  std::future<StatusOr<double>> derived;
  if (!vopt.voxel_size) {
    ASSIGN_OR_RETURN(PointBatch sample, SpacingSample(*framed.reader));
    derived = std::async(std::launch::async, [sample = std::move(sample)] { return VoxelSizeFromSample(sample); });
    vopt.voxel_size_after_survey = [&derived] { return derived.get(); };
    out.voxel_size_derived = true;
  } else if (!(*vopt.voxel_size > 0) || !std::isfinite(*vopt.voxel_size)) {
    return InvalidArgument("voxel size must be a positive number");
  }
  vopt.max_points_in_memory = options.max_points_in_memory;
  vopt.spill_dir = options.spill_dir;
  vopt.progress = [&](uint64_t done, uint64_t total) { report("voxelize", total ? double(done) / double(total) : 0); };
  ASSIGN_OR_RETURN(out.grid, Voxelize(*framed.reader, vopt));
  out.scan = framed.reader->info();
  report("voxelize", 1);
  const auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  out.voxelize_seconds = since(start);
  auto stage_start = std::chrono::steady_clock::now();

  // Draco is one thread: it runs beside the tiles (which fill the cores but idle at their end)
  // rather than after them.
  auto draco = std::async(std::launch::async, [&] {
    const auto draco_start = std::chrono::steady_clock::now();
    auto result = DracoEncodeVoxels(out.grid, DracoSearch::kBestLevel);
    out.compare_seconds = since(draco_start);
    return result;
  });
  TilingOptions tiling = IngestTilingOptions(options.tile_depth, options.quality_db);
  tiling.progress = [&](uint64_t done, uint64_t total) { report("tile", double(done) / double(total)); };
  auto tiles = BuildTiles(out.grid, out.scan, path.filename().string(), tiling);
  out.tile_seconds = since(stage_start);
  report("compare", 0);
  auto compared = draco.get();
  ASSIGN_OR_RETURN(out.tiles, std::move(tiles));
  ASSIGN_OR_RETURN(out.draco, std::move(compared));
  report("compare", 1);
  out.seconds = since(start);
  return out;
}

}  // namespace pointdag
