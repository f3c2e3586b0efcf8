// The daemon's pipeline, one call per uploaded scan:
//
//   read -> georeference (ENU metres when the scan has a CRS) -> voxelize -> LOD tiles, and beside
//   them (one thread) Draco on the finest voxels
//
// Contract: the finest level is exactly what `pointdag encode --georeference` voxelizes from the
// same file at the same voxel size (same frame, same origin, same codes). Without a voxel size the
// median nearest-neighbour spacing of the scan's first 65,536 points is rounded up to a 1-2-5 step.
// Errors are the stages' own Status codes (kInvalidArgument for a CRS or voxel size that cannot
// work, kMalformed/kTruncated/kUnsupported from the readers).
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string_view>

#include "pointdag/compare/draco_compare.h"
#include "pointdag/tile/tiler.h"

namespace pointdag {

// (stage, fraction of that stage done); stages: "survey", "voxelize", "tile", "compare".
using StageProgressFn = std::function<void(std::string_view stage, double fraction)>;

struct IngestOptions {
  std::optional<double> voxel_size;  // ENU metres, or the scan's own units without a CRS
  std::optional<int> epsg;           // CRS override
  std::optional<double> quality_db;  // VBR target PSNR-Y of the tiles' colors; nullopt: 38 dB
  int tile_depth = 8;
  uint64_t max_points_in_memory = uint64_t{1} << 25;
  std::filesystem::path spill_dir;
  StageProgressFn progress;
};

struct IngestedScan {
  ScanInfo scan;
  GeoFrame frame;
  VoxelGrid grid;  // the finest level
  bool voxel_size_derived = false;
  TileSet tiles;
  DracoResult draco;
  double seconds = 0;  // the whole call
  double voxelize_seconds = 0, tile_seconds = 0, compare_seconds = 0;  // Draco's overlaps the tiles'

};

StatusOr<IngestedScan> IngestScan(const std::filesystem::path& path, const IngestOptions& options);

// How IngestScan cuts the finest voxels into tiles (VBR colors at quality_db, 38 dB when not given),
// for anyone who must cut the same tiles (`pointdag export`).
TilingOptions IngestTilingOptions(int tile_depth, std::optional<double> quality_db);

// A voxel size from point spacing: the smallest 1-2-5 step (…, 0.1, 0.2, 0.5, 1, 2, …) >= spacing.
double RoundUpTo125(double spacing);

// The voxel size pointdagd gives a scan uploaded without one: RoundUpTo125 of the median spacing of
// its first 65,536 points, in the reader's units; the reader is rewound. kInvalidArgument for a
// scan without points or whose first points all coincide.
StatusOr<double> DeriveVoxelSize(ScanReader& reader);

// For a process that ingests scan after scan (pointdagd, `bench --ingest`): freed buffers below
// 32 MiB stay in the heap for the next upload instead of going back to the kernel, which would
// fault them in again as zeroed pages (glibc only; elsewhere it does nothing).
void RetainFreedMemory();

}  // namespace pointdag
