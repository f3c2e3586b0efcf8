// pointdag: the codec on the command line.
//   pointdag encode IN -o OUT.pdag (--voxel SIZE | --depth D) [--coder context|zstd]
//   pointdag decode IN.pdag -o OUT.ply
//   pointdag info IN.pdag [--json]
//   pointdag compare IN (--voxel SIZE | --depth D) [--json]
//   pointdag bench [--data DIR] [--json]    (--shadow [DIR]: shadow_bench.h)
//   pointdag export IN.pdag|URL --3dtiles DIR
//   pointdag shadow IN (--direction X,Y,Z | --time ISO8601 [--until ISO8601 --samples N]) (--voxel S | --depth D)
//                   [--json] [-o OUT.ply|OUT.pdsh]   (shadow_command.h)
// Exit codes: 0 ok, 1 bad input (message on stderr), 2 usage.
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "bench.h"
#include "export_3dtiles.h"
#include "pointdag/compare/scorecard.h"
#include "pointdag/container/json_fields.h"
#include "pointdag/gpu/stage_device.h"
#include "pointdag/json_text.h"
#include "client.h"
#include "pointdag/pipeline.h"
#include "pointdag/write/ply_writer.h"
#include "progress.h"
#include "shadow_bench.h"
#include "shadow_command.h"

namespace pointdag {
namespace {

constexpr int kExitBadInput = 1;
constexpr double kDefaultQualityDb = 38.0;

int Fail(const Status& status) {
  std::cerr << "pointdag: " << status.ToString() << "\n";
  return kExitBadInput;
}

struct GridChoice {
  std::optional<double> voxel;
  std::optional<int> depth;
  bool mipmap = false;
  bool georeference = false;
  std::optional<int> epsg;
  uint64_t chunk_points = EncodeOptions{}.max_points_in_memory;
};

void AddGridOptions(CLI::App* cmd, GridChoice& choice) {
  auto* voxel = cmd->add_option("--voxel", choice.voxel, "voxel size in the scan's units")->check(CLI::PositiveNumber);
  auto* depth = cmd->add_option("--depth", choice.depth, "grid depth: 2^D voxels per side")->check(CLI::Range(2, 21));
  voxel->excludes(depth);
  depth->excludes(voxel);
  cmd->add_option("--chunk-points", choice.chunk_points,
                  "most points sorted in memory; larger scans go through spatial chunks on disk")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--mipmap", choice.mipmap, "give internal DAG nodes colors too (mean of their children), for LOD");
}

EncodeOptions MakeEncodeOptions(const GridChoice& choice, const std::string& input) {
  EncodeOptions options;
  options.voxel_size = choice.voxel;
  options.depth = choice.depth;
  options.max_points_in_memory = choice.chunk_points;
  options.mipmap = choice.mipmap;
  options.progress = MakeProgressBar(input);
  return options;
}

struct ColorChoice {
  std::optional<double> quality;
  bool lossless = false;
  std::optional<std::string> codec;
  std::string curve = "hilbert";
};

// --lossless (the default), --quality DB (vbr unless --color-codec says fixed3), or --color-codec.
StatusOr<ColorEncodeOptions> MakeColorOptions(const ColorChoice& choice) {
  ColorEncodeOptions options{ColorCodec::kLossless, std::nullopt};
  if (choice.codec) {
    ASSIGN_OR_RETURN(options.codec, ParseColorCodec(*choice.codec));
  } else if (choice.quality) {
    options.codec = ColorCodec::kVariableRate;
  }
  const bool lossy = IsLossy(options.codec);
  if (choice.quality && !lossy) return InvalidArgument("--quality needs a lossy color codec (vbr, fixed3, jpeg, webp, astc)");
  if (choice.curve == "morton") options.curve = Curve::kMorton;
  options.target_psnr_y = lossy ? std::optional<double>(choice.quality.value_or(kDefaultQualityDb)) : std::nullopt;
  return options;
}

int RunFetch(const std::string& url, std::optional<int> level, const std::string& output, bool shadows) {
  const auto start = std::chrono::steady_clock::now();
  auto fetched = client::FetchDataset(url, level, {}, {}, shadows);
  if (!fetched.ok()) return Fail(fetched.status());
  // --shadows: each voxel's lit fraction (its shadow layer's byte / 255) as the property `light`.
  std::vector<float> light(fetched->light.size());
  std::transform(fetched->light.begin(), fetched->light.end(), light.begin(), [](uint8_t b) { return static_cast<float>(b) / 255.0f; });
  const auto scalar = shadows ? std::optional<PlyScalar>(PlyScalar{"light", light}) : std::nullopt;
  if (Status s = WriteVoxelsPly(output, fetched->grid, scalar); !s.ok()) return Fail(s);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::fprintf(stderr, "%s: level %d, %zu tiles (%llu bytes), %zu voxels of %.6g in %.2f s\n", output.c_str(), fetched->level,
               fetched->tiles, static_cast<unsigned long long>(fetched->tile_bytes), fetched->grid.morton.size(),
               fetched->grid.voxel_size, seconds);
  return 0;
}

int RunExport(const std::string& source, const std::string& dir) {
  const bool remote = source.rfind("http://", 0) == 0;
  const auto report = remote ? ExportTiles3dFromUrl(source, dir) : ExportTiles3dFromPdag(source, dir);
  if (!report.ok()) return Fail(report.status());
  std::fprintf(stderr, "%s: %zu tiles, %llu bytes of .pdag -> %llu bytes of .glb + tileset.json %llu bytes; transcoded in %.2f s, all in %.2f s\n",
               dir.c_str(), report->tiles, static_cast<unsigned long long>(report->pdag_bytes),
               static_cast<unsigned long long>(report->glb_bytes), static_cast<unsigned long long>(report->tileset_bytes),
               report->transcode_seconds, report->seconds);
  return 0;
}

int RunEncode(const std::string& input, const std::string& output, const GridChoice& choice, GeometryCoder coder,
              const ColorEncodeOptions& colors) {
  EncodeOptions options = MakeEncodeOptions(choice, input);
  options.georeference = choice.georeference || choice.epsg.has_value();
  options.epsg = choice.epsg;
  options.geometry_coder = coder;
  options.colors = colors;
  auto encoded = EncodeScan(input, options);
  if (!encoded.ok()) return Fail(encoded.status());
  if (Status s = WritePdag(output, encoded->file); !s.ok()) return Fail(s);
  const double voxels = static_cast<double>(encoded->grid.morton.size());
  std::fprintf(stderr, "%s: %llu points -> %zu voxels (depth %d, voxel %.6g), geometry %.3f bits/voxel",
               output.c_str(), static_cast<unsigned long long>(encoded->grid.points_in), encoded->grid.morton.size(),
               encoded->grid.depth, encoded->grid.voxel_size, 8.0 * static_cast<double>(encoded->file.geometry.size()) / voxels);
  if (encoded->grid.has_color()) {
    std::fprintf(stderr, ", colors (%s) %.3f bits/voxel at PSNR-Y %.2f dB", ColorCodecName(encoded->colors.codec),
                 8.0 * static_cast<double>(encoded->file.colors.size()) / voxels, encoded->colors.psnr.y);
    if (encoded->colors.encodes > 0) std::fprintf(stderr, " (%.2f encodes)", encoded->colors.encodes);
  }
  std::fprintf(stderr, "\n");
  return 0;
}

int RunDecode(const std::string& input, const std::string& output) {
  auto file = ReadPdag(input);
  if (!file.ok()) return Fail(file.status());
  auto decoded = DecodePdag(*file);
  if (!decoded.ok()) return Fail(decoded.status());
  if (Status s = WriteVoxelsPly(output, decoded->grid); !s.ok()) return Fail(s);
  std::fprintf(stderr, "%s: %zu voxels\n", output.c_str(), decoded->grid.morton.size());
  return 0;
}

// The text form of `info`: optional metadata read through checked accessors (a hostile file's
// wrong types are refused, never thrown).
Status PrintInfo(const std::string& input, size_t file_bytes, const PdagFile& file, const DecodedPdag& decoded,
                 const nlohmann::json& out) {
  const JsonFields m(file.meta, ".pdag metadata");
  ASSIGN_OR_RETURN(const std::string name, m.StringOr("source/name", "?"));
  ASSIGN_OR_RETURN(const std::string format, m.StringOr("source/format", "?"));
  ASSIGN_OR_RETURN(const std::string version, m.StringOr("source/version", ""));
  ASSIGN_OR_RETURN(const uint64_t points, m.UintOr("source/points", std::numeric_limits<uint64_t>::max(), 0));
  ASSIGN_OR_RETURN(const std::string geometry_coder, m.StringOr("codec/geometry", "?"));
  ASSIGN_OR_RETURN(const std::string color_codec, m.StringOr("codec/colors/codec", "?"));
  std::optional<double> psnr_y;
  if (m.Has("codec/colors/psnr_y")) {
    ASSIGN_OR_RETURN(psnr_y, m.Number("codec/colors/psnr_y"));
  }
  ASSIGN_OR_RETURN(const std::string wkt, m.StringOr("crs/wkt", ""));
  const size_t voxels = decoded.grid.morton.size();
  std::printf("file        %s (%zu bytes)\n", input.c_str(), file_bytes);
  std::printf("source      %s (%s %s), %llu points\n", name.c_str(), format.c_str(), version.c_str(),
              static_cast<unsigned long long>(points));
  std::printf("grid        depth %d, voxel %.6g, origin (%.3f, %.3f, %.3f)\n", decoded.grid.depth, decoded.grid.voxel_size,
              decoded.grid.origin[0], decoded.grid.origin[1], decoded.grid.origin[2]);
  std::printf("voxels      %zu (%zu unique DAG nodes)\n", voxels, decoded.dag.UniqueNodeCount());
  std::printf("geometry    %zu bytes, %.3f bits/voxel (%s)\n", file.geometry.size(),
              out["bits_per_voxel"]["geometry"].get<double>(), geometry_coder.c_str());
  std::printf("colors      %zu bytes, %.3f bits/voxel (%s", file.colors.size(), out["bits_per_voxel"]["colors"].get<double>(),
              color_codec.c_str());
  if (psnr_y) std::printf(", PSNR-Y %.2f dB", *psnr_y);
  std::printf(")\n");
  std::printf("crs         %s\n", wkt.empty() ? "none (local frame)" : (wkt.substr(0, 72) + (wkt.size() > 72 ? "..." : "")).c_str());
  return Status::Ok();
}

int RunInfo(const std::string& input, bool json) {
  auto bytes = ReadFileBytes(input);
  if (!bytes.ok()) return Fail(bytes.status());
  auto file = ParsePdag(*bytes);
  if (!file.ok()) return Fail(file.status());
  auto decoded = DecodePdag(*file);  // info vouches for the whole file, not just its header
  if (!decoded.ok()) return Fail(decoded.status());
  const auto per_voxel = [&](size_t bytes_count) {
    return 8.0 * static_cast<double>(bytes_count) / static_cast<double>(decoded->grid.morton.size());
  };
  nlohmann::json out = {
      {"file_bytes", bytes->size()},
      {"voxels", decoded->grid.morton.size()},
      {"depth", decoded->grid.depth},
      {"voxel_size", decoded->grid.voxel_size},
      {"unique_nodes", decoded->dag.UniqueNodeCount()},
      {"sections", {{"meta", DumpJson(file->meta).size()}, {"geometry", file->geometry.size()}, {"colors", file->colors.size()}}},
      {"bits_per_voxel", {{"geometry", per_voxel(file->geometry.size())},
                          {"colors", per_voxel(file->colors.size())},
                          {"file", per_voxel(bytes->size())}}},
      {"meta", file->meta},
  };
  if (json) {
    std::cout << DumpJson(out, 2) << "\n";
    return 0;
  }
  if (Status s = PrintInfo(input, bytes->size(), *file, *decoded, out); !s.ok()) return Fail(s);
  return 0;
}

// The scorecard: geometry, every color codec at 30/34/38/42 dB and lossless, Draco on the same voxels.
int RunCompare(const std::string& input, const GridChoice& choice, bool json) {
  auto encoded = EncodeScan(input, MakeEncodeOptions(choice, input));
  if (!encoded.ok()) return Fail(encoded.status());
  auto scorecard = BuildScorecard(*encoded);
  if (!scorecard.ok()) return Fail(scorecard.status());
  nlohmann::json& out = *scorecard;
  out["input"] = input;
  const nlohmann::json& codecs = out["codecs"];
  if (json) {
    std::cout << DumpJson(out, 2) << "\n";
    return 0;
  }
  std::printf("%s: %llu points -> %zu voxels (depth %d, voxel %.6g)\n", input.c_str(),
              static_cast<unsigned long long>(encoded->grid.points_in), encoded->grid.morton.size(), encoded->grid.depth,
              encoded->grid.voxel_size);
  std::printf("  geometry bits/voxel: resident SVDAG %.3f, stored zstd %.3f, stored context coder %.3f\n",
              out["geometry"]["resident_bits_per_voxel"].get<double>(), out["geometry"]["stored_zstd_bits_per_voxel"].get<double>(),
              out["geometry"]["stored_context_bits_per_voxel"].get<double>());
  std::printf("  Draco, lossless, same voxels: %.3f bits/point (%s, speed %d); kd-tree at -cl 10 encodes in %.3f s\n",
              out["draco_bits_per_point"].get<double>(), out["draco"]["method"].get<std::string>().c_str(),
              out["draco"]["speed"].get<int>(), out["draco"]["level10_encode_s"].get<double>());
  const auto& orig = out["original"];
  std::printf("  voxels vs original points: D1 MSE %.3g, D1 PSNR %s dB, voxel colors PSNR-Y %s dB\n", orig["d1_mse"].get<double>(),
              orig["d1_psnr"].is_null() ? "inf" : std::to_string(orig["d1_psnr"].get<double>()).substr(0, 5).c_str(),
              orig["psnr_y_voxel_colors"].is_null() ? "-" : std::to_string(orig["psnr_y_voxel_colors"].get<double>()).substr(0, 5).c_str());
  if (!codecs.empty()) {
    std::printf("  %-13s %8s %8s %9s %12s %12s %14s\n", "colors", "target", "PSNR-Y", "vs orig", "color b/vox", "total b/vox",
                "Draco / ours");
    for (const auto& c : codecs) {
      const std::string target = c["target_psnr"].is_null() ? "-" : std::to_string(c["target_psnr"].get<int>()) + " dB";
      const std::string name = c["name"].get<std::string>() + (c["curve"].is_null() ? "" : "/" + c["curve"].get<std::string>());
      const std::string psnr = c["psnr_y"].is_null() ? "exact" : std::to_string(c["psnr_y"].get<double>()).substr(0, 5);
      const std::string vs_original =
          c["psnr_y_vs_original"].is_null() ? "-" : std::to_string(c["psnr_y_vs_original"].get<double>()).substr(0, 5);
      std::printf("  %-13s %8s %8s %9s %12.3f %12.3f %13.2fx\n", name.c_str(), target.c_str(), psnr.c_str(), vs_original.c_str(),
                  c["color_bits_per_voxel"].get<double>(), c["total_bits_per_voxel"].get<double>(),
                  c["draco_over_ours"].get<double>());
    }
  }
  return 0;
}

int Main(int argc, char** argv) {
  CLI::App app{"pointdag: point clouds to compressed sparse voxel DAGs"};
  app.require_subcommand(1);
  std::string input, output;
  GridChoice grid;
  bool json = false;
  std::string coder_name = "spatial";

  auto* encode = app.add_subcommand("encode", "voxelize a scan (LAS/PLY/PCD) into a .pdag file");
  encode->add_option("input", input, "scan file")->required();
  encode->add_option("-o,--output", output, "output .pdag")->required();
  AddGridOptions(encode, grid);
  encode->add_option("--coder", coder_name, "geometry entropy coder")->check(CLI::IsMember({"spatial", "context", "zstd"}));
  ColorChoice color_choice;
  encode->add_flag("--georeference", grid.georeference,
                   "voxelize in ENU metres about the scan's centre when it has a CRS (as pointdagd does)");
  encode->add_option("--epsg", grid.epsg, "source CRS override (implies --georeference)")->check(CLI::PositiveNumber);
  auto* quality = encode->add_option("--quality", color_choice.quality,
                                     "target color PSNR-Y in dB (lossy; vbr unless --color-codec fixed3)")
                      ->check(CLI::Range(10.0, 99.0));
  auto* lossless = encode->add_flag("--lossless", color_choice.lossless, "keep colors exact (the default)");
  quality->excludes(lossless);
  encode->add_option("--color-codec", color_choice.codec,
                     "raw, lossless, fixed3, vbr, png, jpeg, webp, astc or hierarchical (the lossy ones default to 38 dB)")
      ->check(CLI::IsMember({"raw", "lossless", "fixed3", "vbr", "png", "jpeg", "webp", "astc", "hierarchical"}));
  encode->add_option("--curve", color_choice.curve, "2D mapping of png/jpeg/webp/astc colors")
      ->check(CLI::IsMember({"hilbert", "morton"}));

  auto* decode = app.add_subcommand("decode", "write a .pdag's voxels (centres + colors) as PLY");
  decode->add_option("input", input, ".pdag file")->required();
  decode->add_option("-o,--output", output, "output .ply")->required();

  auto* info = app.add_subcommand("info", "describe a .pdag file");
  info->add_option("input", input, ".pdag file")->required();
  info->add_flag("--json", json, "print JSON");

  auto* compare = app.add_subcommand("compare", "our sizes against Draco on the same voxels");
  compare->add_option("input", input, "scan file")->required();
  AddGridOptions(compare, grid);
  compare->add_flag("--json", json, "print JSON");

  std::string url;
  std::optional<int> level;
  auto* fetch = app.add_subcommand("fetch", "download a dataset's tiles from pointdagd and decode them to points");
  fetch->add_option("url", url, "http://HOST:PORT/v1/datasets/ID")->required();
  fetch->add_option("--level", level, "level of detail (0 = coarsest; default: the finest)")->check(CLI::NonNegativeNumber);
  fetch->add_option("-o,--output", output, "output .ply (voxel centres in the dataset's frame + RGB)")->required();
  bool fetch_shadows = false;
  fetch->add_flag("--shadows", fetch_shadows, "also the dataset's shadow layers: a float property `light` (lit fraction 0..1)");

  std::string tiles3d_dir;
  auto* export_cmd = app.add_subcommand("export", "a dataset (a .pdag, or a pointdagd URL) as 3D Tiles 1.1 static files");
  export_cmd->add_option("input", input, "IN.pdag or http://HOST:PORT/v1/datasets/ID")->required();
  export_cmd->add_option("--3dtiles", tiles3d_dir, "output folder: tileset.json and {level}/{x}/{y}/{z}.glb")->required();

  ShadowCommand shadow_command;
  auto* shadow = AddShadowCommand(app, shadow_command);

  BenchOptions bench_options;
  auto* bench = app.add_subcommand("bench", "benchmark every scan in a folder (read, voxelize, build, sizes, Draco)");
  bench->add_option("--data", bench_options.data_dir, "folder of scans")->check(CLI::ExistingDirectory);
  bench->add_flag("--json", bench_options.json, "print JSON lines instead of a table");
  bench->add_flag("--colors", bench_options.colors, "color codecs: rate-distortion table and decoding speed");
  bench->add_flag("--ingest", bench_options.ingest, "the daemon's ingest pipeline per scan: stage times, points/s, peak RSS");
  bench->add_flag("--devices", bench_options.devices, "each stage with Vulkan kernels on the CPU and on Vulkan: points/s");
  bench->add_option("--chunk-points", bench_options.max_points_in_memory, "as for encode")->check(CLI::PositiveNumber);
  bench->add_flag("--laz", bench_options.laz, "LAZ decoding of DATA/laz: points/s on one core and all; LAZ vs LAS ingest");
  bench->add_option("--server", bench_options.server,
                    "upload each scan twice to the pointdagd at this URL (POINTDAGD_TOKEN if it needs one): end-to-end seconds and points/s");
  bench->add_flag("--versus", bench_options.versus, "ours, Draco and G-PCC side by side: geometry, colors at 34/38/42 dB, lossless totals");
  std::string shadow_bench_dir;
  auto* shadow_bench = bench->add_option("--shadow", shadow_bench_dir,
                                         "shadow DAGs of every scan in DIR (default: --data) at two resolutions: sizes "
                                         "against the dense grid and a shadow map, build time, memory, queries/s")
                           ->expected(0, 1);
  auto* corpus = bench->add_option("--corpus", bench_options.corpus,
                                   "nightly benchmark: a corpus TOML file or a folder of scans (docs/nightly.md)")
                     ->check(CLI::ExistingPath);
  bench->add_option("--out", bench_options.out_dir, "where --corpus writes report-ID.json and .html")->needs(corpus);
  corpus->needs(bench->get_option("--out"));
  bench->add_option("--baseline", bench_options.baseline, "report to compare with (default: the newest in --out)")
      ->check(CLI::ExistingFile)
      ->needs(corpus);
  bench->add_option("--size-tolerance", bench_options.size_tolerance, "relative growth of a size that fails the run")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  bench->add_option("--psnr-tolerance", bench_options.psnr_tolerance, "PSNR-Y drop in dB that fails the run")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  bench->add_option("--keep", bench_options.keep_reports, "reports kept in --out (0: all)")->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  for (auto* cmd : {encode, compare}) {
    if (cmd->parsed() && !grid.voxel && !grid.depth) {
      std::cerr << "pointdag " << cmd->get_name() << ": give --voxel SIZE or --depth D\n";
      return 2;
    }
  }
  if (encode->parsed() || compare->parsed()) {
    // A bad POINTDAG_DEVICE, or `vulkan` without a device, is the caller's to fix: say so first.
    if (const auto device = gpu::ProcessDevice(); !device.ok()) {
      std::cerr << "pointdag " << app.get_subcommands().front()->get_name() << ": " << device.status().message() << "\n";
      return 2;
    }
  }
  if (bench->parsed()) {  // its cases run in forked children, which open Vulkan themselves
    const char* device = std::getenv("POINTDAG_DEVICE");
    if (const auto choice = gpu::ParseDeviceChoice(device ? device : "auto"); !choice.ok()) {
      std::cerr << "pointdag bench: " << choice.status().message() << "\n";
      return 2;
    }
  }
  if (encode->parsed()) {
    auto colors = MakeColorOptions(color_choice);
    if (!colors.ok()) {
      std::cerr << "pointdag encode: " << colors.status().message() << "\n";
      return 2;
    }
    return RunEncode(input, output, grid, coder_name == "zstd"      ? GeometryCoder::kZstd
                                                : coder_name == "context" ? GeometryCoder::kContext
                                                                          : GeometryCoder::kSpatial, *colors);
  }
  if (decode->parsed()) return RunDecode(input, output);
  if (info->parsed()) return RunInfo(input, json);
  if (compare->parsed()) return RunCompare(input, grid, json);
  if (bench->parsed() && shadow_bench->count() > 0) {
    return RunShadowBench(shadow_bench_dir.empty() ? bench_options.data_dir : shadow_bench_dir, std::cout);
  }
  if (bench->parsed()) return RunBench(bench_options);
  if (fetch->parsed()) return RunFetch(url, level, output, fetch_shadows);
  if (export_cmd->parsed()) return RunExport(input, tiles3d_dir);
  if (shadow->parsed()) return RunShadowCommand(shadow_command);
  return 2;
}

}  // namespace
}  // namespace pointdag

// Last resort only: every input error is a Status by design; an exception that still escapes
// (bad_alloc on a machine short of memory, a library's own throw) ends in a reason and exit 1.
int main(int argc, char** argv) {
  try {
    return pointdag::Main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "pointdag: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "pointdag: unknown error\n";
  }
  return 1;
}
