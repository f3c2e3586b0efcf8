// The codec's front door: scan file -> .pdag and back, stage by stage.
//
//   read (read/) -> voxelize (voxelize/) -> build DAG (dag/dag_builder) -> stored form
//   (dag/dag_stream) -> colors (color/) -> container (container/)
//
//   colors (color/): raw, lossless, or the block codecs of Papers IIA/IIB at a target PSNR
//
//   georeferencing (georef/) wraps the reader when asked; tiling (tile/) cuts a voxel grid into LOD tiles
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "pointdag/color/color_codec.h"
#include "pointdag/container/pdag_file.h"
#include "pointdag/dag/dag_stream.h"
#include "pointdag/dag/svdag.h"
#include "pointdag/georef/georeference.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

struct EncodeOptions {
  std::optional<double> voxel_size;  // exactly one of voxel_size and depth
  std::optional<int> depth;
  GeometryCoder geometry_coder = GeometryCoder::kSpatial;
  int geometry_version = kGeometryStreamVersion;  // of the spatial coder's stream (dag_stream.h)
  ColorEncodeOptions colors{ColorCodec::kLossless, std::nullopt};
  bool mipmap = false;  // DAG counts nodes and internal nodes get colors too (Paper IIB)
  uint64_t max_points_in_memory = uint64_t{1} << 25;  // above it, voxelize and build chunk by chunk
  std::filesystem::path spill_dir;                    // chunk files; empty: the system's temp folder
  ProgressFn progress;
  bool georeference = false;   // read in ENU metres about the scan's centre when it has a CRS (georef/)
  std::optional<int> epsg;     // CRS override for georeferencing
};

struct StageSeconds {
  double read_voxelize = 0;  // reading, quantizing, sorting and averaging
  double build = 0;          // DAG building and merging (interleaved with voxelizing when chunked)
  double encode = 0;         // geometry stored form
  double colors = 0;         // color codec, including its quality search
};

struct EncodedScan {
  std::filesystem::path source;
  ScanInfo scan;
  GeoFrame frame;  // georeferenced only with EncodeOptions::georeference
  VoxelGrid grid;
  Svdag dag;
  PdagFile file;
  EncodedColors colors;  // empty bytes when the scan has no color
  StageSeconds seconds;
};

// Decides now where each stage with Vulkan kernels runs (gpu/pointdag/gpu/stage_device.h), as the
// daemon does at start to log and export the choice; otherwise the first use decides. An error when
// POINTDAG_DEVICE is unknown, or is `vulkan` and no device opens.
Status ChooseStageDevices();

StatusOr<EncodedScan> EncodeScan(const std::filesystem::path& input, const EncodeOptions& options);

// The stages after voxelizing, for a grid already in memory (a tile): DAG, stored form, colors.
StatusOr<EncodedScan> EncodeGrid(VoxelGrid grid, const ScanInfo& scan, const std::string& source_name,
                                 const EncodeOptions& options);

// Metadata JSON for a voxelized scan (source, CRS, grid, counts, codec parameters).
nlohmann::json DescribeScan(const std::string& source_name, const ScanInfo& scan, const VoxelGrid& grid,
                            const Svdag& dag, GeometryCoder coder, const EncodedColors& colors,
                            const ColorEncodeOptions& color_options);

// The metadata stays in the PdagFile it was parsed into: a decode copies none of it.
struct DecodedPdag {
  Svdag dag;
  VoxelGrid grid;               // Morton codes from the DAG, voxel colors from the colors section
  // Mipmap mode, files that store every node's color (written before voxel-only sections,
  // kVoxelColorsOnly): those, in pre-order (index = MipColorIndex). Otherwise empty:
  // BuildMipColors(grid.morton, grid.colors, grid.depth) derives them.
  std::vector<Rgb8> mip_colors;
};

// What a decode may produce, whatever the file declares: a .pdag of a few hundred bytes can
// describe a DAG of 8^21 voxels, so the caller's memory, not the file, sets the bound.
// The defaults hold every scan and tile we know with room to spare (tiles hold at most 2^24 voxels)
// and keep a decode under a few GB.
struct DecodeLimits {
  uint64_t max_voxels = uint64_t{1} << 27;  // voxels, and in mipmap mode node colors
  uint64_t max_nodes = uint64_t{1} << 25;   // unique DAG nodes (a decode holds ~60 bytes per node)
};

StatusOr<DecodedPdag> DecodePdag(const PdagFile& file, const DecodeLimits& limits = {});

}  // namespace pointdag
