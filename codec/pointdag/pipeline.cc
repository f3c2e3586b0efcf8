#include "pointdag/pipeline.h"

#include <chrono>

#include "pointdag/color/block_codec.h"
#include "pointdag/dag/dag_builder.h"

namespace pointdag {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

nlohmann::json DescribeCrs(const ScanInfo& scan) {
  nlohmann::json crs = {{"wkt", scan.crs_wkt}};
  if (scan.geokeys) {
    nlohmann::json keys = nlohmann::json::array();
    for (const GeoKey& k : scan.geokeys->keys) keys.push_back({k.id, k.location, k.count, k.value});
    crs["geokeys"] = {{"keys", keys}, {"doubles", scan.geokeys->doubles}, {"ascii", scan.geokeys->ascii}};
    // GeoTIFF: ProjectedCSTypeGeoKey (3072) or GeographicTypeGeoKey (2048); 32767 means user-defined.
    for (const GeoKey& k : scan.geokeys->keys) {
      if ((k.id == 3072 || k.id == 2048) && k.location == 0 && k.value != 32767 && k.value != 0) crs["epsg"] = k.value;
    }
  }
  return crs;
}

// The stages after the DAG: its stored form, the colors, the metadata.
Status EncodeAfterDag(const EncodeOptions& options, EncodedScan& out) {
  auto start = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(out.file.geometry, EncodeDag(out.dag, options.geometry_coder, options.geometry_version));
  out.seconds.encode = SecondsSince(start);

  start = std::chrono::steady_clock::now();
  if (out.grid.has_color()) {
    // Mipmap mode stores the voxels' colors as leaf mode does, flagged: the internal nodes' are
    // their children's means, derived by a reader that wants them (kVoxelColorsOnly).
    ASSIGN_OR_RETURN(out.colors, EncodeColors(out.grid.colors, options.colors, out.grid.morton));
    if (options.mipmap) out.colors.bytes[0] |= kVoxelColorsOnly;
    out.file.colors = out.colors.bytes;
  }
  out.seconds.colors = SecondsSince(start);
  out.file.meta = DescribeScan(out.source.filename().string(), out.scan, out.grid, out.dag, options.geometry_coder,
                               out.colors, options.colors);
  if (options.georeference) out.file.meta["frame"] = DescribeFrame(out.frame);
  return Status::Ok();
}

}  // namespace

nlohmann::json DescribeScan(const std::string& source_name, const ScanInfo& scan, const VoxelGrid& grid,
                            const Svdag& dag, GeometryCoder coder, const EncodedColors& colors,
                            const ColorEncodeOptions& color_options) {
  nlohmann::json color = {{"codec", grid.has_color() ? ColorCodecName(colors.codec) : "none"}};
  if (grid.has_color()) {
    color["target_psnr_y"] = color_options.target_psnr_y ? nlohmann::json(*color_options.target_psnr_y) : nlohmann::json();
    if (IsLossy(colors.codec)) {
      color["max_mse"] = colors.max_mse;
      color["blocks"] = colors.blocks;
      color["psnr_y"] = colors.psnr.y;
      color["psnr_rgb"] = colors.psnr.rgb;
    }
  }
  const double side = grid.voxel_size * std::ldexp(1.0, grid.depth);
  nlohmann::json source = {{"name", source_name},
                           {"format", ScanFormatName(scan.format)},
                           {"version", scan.format_version},
                           {"points", grid.points_in},
                           {"color_bits", grid.has_color() ? grid.source_color_bits : 0}};
  if (scan.las_point_format >= 0) source["las_point_format"] = scan.las_point_format;
  return {
      {"generator", "pointdag 0.1.0"},
      {"source", source},
      {"crs", DescribeCrs(scan)},
      {"depth", grid.depth},
      {"voxel_size", grid.voxel_size},
      {"origin", grid.origin},
      {"grid_bounds", {{"min", grid.origin},
                       {"max", {grid.origin[0] + side, grid.origin[1] + side, grid.origin[2] + side}}}},
      {"voxels", grid.morton.size()},
      {"unique_nodes", dag.UniqueNodeCount()},
      {"has_color", grid.has_color()},
      {"codec", {{"geometry", GeometryCoderName(coder)},
                 {"count_mode", dag.mode == CountMode::kMipmap ? "mipmap" : "leaves"},
                 {"colors", color}}},
  };
}

Status ChooseStageDevices() {
  RETURN_IF_ERROR(VoxelizeDevice().status());
  RETURN_IF_ERROR(DagHashesDevice().status());
  return ColorBlocksDevice().status();
}

StatusOr<EncodedScan> EncodeScan(const std::filesystem::path& input, const EncodeOptions& options) {
  EncodedScan out;
  out.source = input;
  auto start = std::chrono::steady_clock::now();
  std::unique_ptr<ScanReader> reader;
  if (options.georeference) {
    ASSIGN_OR_RETURN(FramedReader framed, OpenScanInFrame(input, options.epsg));
    reader = std::move(framed.reader);
    out.frame = std::move(framed.frame);
  } else {
    ASSIGN_OR_RETURN(reader, OpenScan(input));
  }
  VoxelizeOptions vopt;
  vopt.voxel_size = options.voxel_size;
  vopt.depth = options.depth;
  vopt.max_points_in_memory = options.max_points_in_memory;
  vopt.spill_dir = options.spill_dir;
  vopt.progress = options.progress;
  // Each voxelized chunk becomes a sub-DAG merged at once (Paper I), so no stage holds every point.
  std::optional<DagMerger> merger;
  vopt.on_chunk = [&](const VoxelGrid& grid, size_t first_voxel) -> Status {
    const auto chunk_start = std::chrono::steady_clock::now();
    if (!merger) {
      DagBuildOptions dag_options;
      dag_options.mode = options.mipmap ? CountMode::kMipmap : CountMode::kLeaves;
      ASSIGN_OR_RETURN(DagMerger created, DagMerger::Create(grid.depth, grid.chunk_levels, dag_options));
      merger.emplace(std::move(created));
    }
    const Status status = merger->AddChunk(std::span(grid.morton).subspan(first_voxel));
    out.seconds.build += SecondsSince(chunk_start);
    return status;
  };
  ASSIGN_OR_RETURN(out.grid, Voxelize(*reader, vopt));
  out.scan = reader->info();
  if (!merger) return Internal("voxelizing produced no chunk");
  const auto finish_start = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(out.dag, merger->Finish());
  out.seconds.build += SecondsSince(finish_start);
  out.seconds.read_voxelize = SecondsSince(start) - out.seconds.build;

  RETURN_IF_ERROR(EncodeAfterDag(options, out));
  return out;
}

StatusOr<EncodedScan> EncodeGrid(VoxelGrid grid, const ScanInfo& scan, const std::string& source_name,
                                 const EncodeOptions& options) {
  EncodedScan out;
  out.source = source_name;
  out.scan = scan;
  out.grid = std::move(grid);
  const auto start = std::chrono::steady_clock::now();
  DagBuildOptions dag_options;
  dag_options.mode = options.mipmap ? CountMode::kMipmap : CountMode::kLeaves;
  ASSIGN_OR_RETURN(out.dag, BuildDag(out.grid.morton, out.grid.depth, dag_options));
  out.seconds.build = SecondsSince(start);
  RETURN_IF_ERROR(EncodeAfterDag(options, out));
  return out;
}

}  // namespace pointdag
