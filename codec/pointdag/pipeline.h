// The codec's front door: scan file -> .pdag and back, stage by stage.
//
//   read (read/) -> voxelize (voxelize/) -> build DAG (dag/dag_builder) -> stored form
//   (dag/dag_stream) -> container (container/)
//
// Georeferencing, color codecs and tiling join this pipeline in later stages; today the colors
// section holds raw 8-bit RGB in color-index (Morton) order.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "pointdag/container/pdag_file.h"
#include "pointdag/dag/dag_stream.h"
#include "pointdag/dag/svdag.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

struct EncodeOptions {
  std::optional<double> voxel_size;  // exactly one of voxel_size and depth
  std::optional<int> depth;
  GeometryCoder geometry_coder = GeometryCoder::kContext;
  uint64_t max_points_in_memory = uint64_t{1} << 25;  // above it, voxelize and build chunk by chunk
  std::filesystem::path spill_dir;                    // chunk files; empty: the system's temp folder
  ProgressFn progress;
};

struct StageSeconds {
  double read_voxelize = 0;  // reading, quantizing, sorting and averaging
  double build = 0;          // DAG building and merging (interleaved with voxelizing when chunked)
  double encode = 0;
};

struct EncodedScan {
  ScanInfo scan;
  VoxelGrid grid;
  Svdag dag;
  PdagFile file;
  StageSeconds seconds;
};

StatusOr<EncodedScan> EncodeScan(const std::filesystem::path& input, const EncodeOptions& options);

// Metadata JSON for a voxelized scan (source, CRS, grid, counts, codec parameters).
nlohmann::json DescribeScan(const std::string& source_name, const ScanInfo& scan, const VoxelGrid& grid,
                            const Svdag& dag, GeometryCoder coder);

struct DecodedPdag {
  nlohmann::json meta;
  Svdag dag;
  VoxelGrid grid;  // Morton codes from the DAG, colors from the colors section
};

StatusOr<DecodedPdag> DecodePdag(const PdagFile& file);

}  // namespace pointdag
