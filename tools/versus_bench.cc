// `pointdag bench --versus`: issue #14's side-by-side table. Ours and Draco measured in this run on
// the same voxels; G-PCC (TMC13 v23, lossless-geometry octree + RAHT) as constants for reference:
// TMC13 is not packaged for Debian, so it was built and run once on exactly these voxels
// (docs/benchmarks.md, "G-PCC measured on our voxels"), at QPs 16..40.
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "bench.h"
#include "process_time.h"
#include "tile_decode_time.h"
#include "pointdag/bench/report.h"
#include "pointdag/compare/draco_compare.h"
#include "pointdag/container/pdag_file.h"
#include "pointdag/pipeline.h"
#include "pointdag/tile/tiler.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

struct RatePoint {
  double psnr_y;
  double bits;
};

struct GpccReference {
  const char* scan;
  double voxel;
  double geometry_bits;         // per voxel
  std::vector<RatePoint> raht;  // color bits per voxel by PSNR-Y, ascending (QP 40 or the first under 30.5 dB .. QP 16)
  double issue_draco_lossless_total = NAN;  // the issue's Draco figure, where it gave one
};

// tmc3 release-v23.0-rc2 with its CTC configuration for lossless geometry and lossy attributes
// (octree-raht-ctc-lossless-geom-lossy-attrs), planar mode on and duplicate points merged (both
// never worse here), colors in YCbCr; bits: its positions and colors bitstream sizes; PSNR-Y over
// the decoded voxels in BT.709 luma as ours. Autzen and guanyin reproduce the issue's constants.
const std::vector<GpccReference> kGpcc = {
    {"autzen_trim_pdrf3_rgb.las", 4.0, 1.721,
     {{29.67, 0.201}, {30.66, 0.269}, {31.68, 0.354}, {32.90, 0.482}, {34.18, 0.643}, {35.62, 0.850},
      {37.08, 1.097}, {38.81, 1.445}, {40.19, 1.747}, {41.76, 2.149}, {43.61, 2.688}, {45.84, 3.124}}, 18.28},
    {"lion_takanawa_pdrf7_rgb.las", 0.01, 2.900,
     {{30.45, 0.866}, {32.01, 1.199}, {33.95, 1.605}, {35.68, 1.997}, {37.88, 2.501}, {39.36, 2.898},
      {41.12, 3.428}, {43.08, 4.096}, {45.62, 4.564}}, 21.61},
    {"pcx_guanyin_cc-by-4.0_rgb.ply", 0.002, 4.921,
     {{30.22, 0.309}, {31.38, 0.444}, {32.77, 0.648}, {34.08, 0.906}, {35.62, 1.212}, {37.08, 1.586},
      {38.93, 2.136}, {40.28, 2.599}, {41.84, 3.229}, {43.66, 4.056}, {45.98, 4.686}}, 20.54},
    {"pcl_milk_cartoon_clorox_kinect_rgb.ply", 0.004, 1.973,
     {{32.45, 0.092}, {33.51, 0.127}, {34.43, 0.172}, {35.38, 0.227}, {36.34, 0.309}, {37.22, 0.442},
      {38.20, 0.640}, {39.17, 0.942}, {40.49, 1.507}, {41.50, 2.052}, {42.67, 2.798}, {44.16, 3.825},
      {46.19, 4.484}}},
    {"ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las", 0.5, 1.343,
     {{29.36, 0.909}, {31.04, 1.204}, {32.66, 1.552}, {34.49, 1.960}, {36.16, 2.436}, {38.19, 3.148},
      {39.67, 3.782}, {41.34, 4.664}, {43.23, 5.786}, {45.66, 6.429}}},
    {"ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las", 0.1, 6.217,
     {{30.15, 0.723}, {31.76, 0.969}, {33.26, 1.272}, {35.03, 1.632}, {36.58, 2.073}, {38.56, 2.772},
      {39.96, 3.383}, {41.58, 4.254}, {43.43, 5.334}, {45.84, 5.988}}},
    {"tiny_1.2-with-color_1065pts.las", 8.0, 13.042,
     {{30.22, 2.611}, {31.56, 3.214}, {34.00, 3.898}, {35.55, 4.771}, {37.65, 5.983}, {39.35, 6.901},
      {41.24, 7.895}, {43.10, 9.046}, {45.64, 10.002}}},
};

// Bits at `psnr` on a rate-distortion curve sorted by PSNR: linear between the two points that
// bracket it, extended along the nearest segment outside.
double BitsAt(const std::vector<RatePoint>& curve, double psnr) {
  if (curve.size() < 2) return curve.empty() ? NAN : curve[0].bits;
  size_t i = 1;
  while (i + 1 < curve.size() && curve[i].psnr_y < psnr) ++i;
  const RatePoint& a = curve[i - 1];
  const RatePoint& b = curve[i];
  if (b.psnr_y == a.psnr_y) return b.bits;
  return a.bits + (b.bits - a.bits) * (psnr - a.psnr_y) / (b.psnr_y - a.psnr_y);
}

// The daemon's LOD tiles of `grid` (VBR colors at its default target) decoded as a client decodes
// them (parse, DAG, colors, mipmaps), best of three passes: points per second, counting each tile's
// voxels (every level's, since a client refining to the finest level decodes the levels above too).
StatusOr<double> TileDecodeRate(const VoxelGrid& grid) {
  ASSIGN_OR_RETURN(const TileSet tiles, BuildTiles(grid, ScanInfo{}, "versus", TilingOptions{}));
  double points = 0;
  for (const Tile& tile : tiles.tiles) points += static_cast<double>(tile.voxels);
  ASSIGN_OR_RETURN(const double best, BestTileDecodeSeconds(tiles, 3));
  return points / best;
}

// The voxels as the issue fed them to both coders: integer voxel coordinates as float32 x y z (what
// draco_encoder reads) and uchar RGB, binary little-endian PLY.
Status WriteVoxelIndexPly(const std::filesystem::path& path, const VoxelGrid& grid) {
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << grid.morton.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
         "property uchar blue\nend_header\n";
  std::vector<char> record(15);
  for (size_t i = 0; i < grid.morton.size(); ++i) {
    const auto cell = MortonDecode(grid.morton[i]);
    for (int axis = 0; axis < 3; ++axis) {
      const auto v = static_cast<float>(cell[axis]);
      std::memcpy(&record[4 * axis], &v, 4);
    }
    const Rgb8 c = grid.has_color() ? grid.colors[i] : Rgb8{};
    record[12] = static_cast<char>(c.r), record[13] = static_cast<char>(c.g), record[14] = static_cast<char>(c.b);
    out.write(record.data(), static_cast<std::streamsize>(record.size()));
  }
  out.close();
  return out ? Status::Ok() : IoError("cannot write " + path.string());
}

// Goal 5 as the issue measures it: whole processes on one core (CPU seconds, best of 3), both coders
// reading the same voxels from one PLY file: `pointdag encode --voxel 1 --quality 38` (and
// `--lossless`) against `draco_encoder -point_cloud -qp 11 -cl 10`, and `pointdag decode` of the
// 38 dB file against `draco_decoder`. Without draco_encoder (Debian's package draco) only ours.
nlohmann::json WholeProcessTimes(const VoxelGrid& grid) {
  std::string dir_template = (std::filesystem::temp_directory_path() / "pointdag-versus-XXXXXX").string();
  if (!mkdtemp(dir_template.data())) return {{"error", "cannot make a temporary folder"}};
  const std::filesystem::path dir = dir_template;
  const auto file = [&](const char* name) { return (dir / name).string(); };
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const std::vector<std::pair<std::string, std::string>> cpu = {{"POINTDAG_DEVICE", "cpu"}};
  constexpr int kRuns = 3;
  nlohmann::json r;
  const auto time = [&](const char* key, std::vector<std::string> argv, std::vector<std::pair<std::string, std::string>> env) {
    auto s = BestProcessCpuSeconds({std::move(argv), std::move(env), 0}, kRuns);
    if (s.ok()) r[key] = *s;
    else r["error"] = s.status().ToString();
  };
  if (Status written = WriteVoxelIndexPly(file("voxels.ply"), grid); !written.ok()) {
    r["error"] = written.ToString();
  } else {
    time("encode_38_s", {self, "encode", file("voxels.ply"), "--voxel", "1", "--quality", "38", "-o", file("q38.pdag")}, cpu);
    time("encode_lossless_s", {self, "encode", file("voxels.ply"), "--voxel", "1", "--lossless", "-o", file("ll.pdag")}, cpu);
    time("decode_38_s", {self, "decode", file("q38.pdag"), "-o", file("q38.ply")}, cpu);
    // The hierarchical colors, where they pay most: not random access, and slower both ways.
    time("encode_hierarchical_34_s", {self, "encode", file("voxels.ply"), "--voxel", "1", "--quality", "34",
                                      "--color-codec", "hierarchical", "-o", file("h34.pdag")}, cpu);
    time("decode_hierarchical_34_s", {self, "decode", file("h34.pdag"), "-o", file("h34.ply")}, cpu);
    const std::string draco_encoder = FindExecutable("draco_encoder"), draco_decoder = FindExecutable("draco_decoder");
    if (draco_encoder.empty() || draco_decoder.empty()) {
      r["draco_missing"] = "draco_encoder/draco_decoder not in PATH (Debian package draco, installed by scripts/setup)";
    } else {
      time("draco_encoder_s", {draco_encoder, "-point_cloud", "-i", file("voxels.ply"), "-o", file("v.drc"), "-qp", "11", "-cl", "10"}, {});
      time("draco_decoder_s", {draco_decoder, "-i", file("v.drc"), "-o", file("v.ply")}, {});
    }
  }
  std::error_code ignored;
  std::filesystem::remove_all(dir, ignored);
  return r;
}

nlohmann::json VersusCase(const std::filesystem::path& scan, const GpccReference& reference) {
  EncodeOptions options;
  options.voxel_size = reference.voxel;
  auto encoded = EncodeScan(scan, options);  // geometry, and lossless colors by default
  if (!encoded.ok()) return {{"error", encoded.status().ToString()}};
  const VoxelGrid& grid = encoded->grid;
  const double voxels = static_cast<double>(grid.morton.size());
  const double geometry = 8.0 * static_cast<double>(encoded->file.geometry.size()) / voxels;
  const double lossless = 8.0 * static_cast<double>(encoded->colors.bytes.size()) / voxels;
  // VBR and the hierarchical colors at targets bracketing 34..42 dB: each curve is interpolated at
  // exactly 34, 38 and 42.
  std::map<ColorCodec, std::vector<RatePoint>> curves;
  for (ColorCodec codec : {ColorCodec::kVariableRate, ColorCodec::kHierarchical}) {
    for (double target : {32.0, 34.0, 36.0, 38.0, 40.0, 42.0, 44.0}) {
      auto colors = EncodeColors(grid.colors, {codec, target}, grid.morton);
      if (!colors.ok()) return {{"error", colors.status().ToString()}};
      curves[codec].push_back({colors->psnr.y, 8.0 * static_cast<double>(colors->bytes.size()) / voxels});
    }
  }
  auto draco = DracoEncodeVoxels(grid);
  if (!draco.ok()) return {{"error", draco.status().ToString()}};
  auto tile_rate = TileDecodeRate(grid);
  if (!tile_rate.ok()) return {{"error", tile_rate.status().ToString()}};
  const nlohmann::json processes = WholeProcessTimes(grid);
  if (processes.contains("error")) return {{"error", processes["error"]}};
  char label[32];  // the scan's name and voxel: IGN is measured at two
  std::snprintf(label, sizeof(label), " @ %g", reference.voxel);
  nlohmann::json r = {{"scan", scan.filename().string()}, {"case", scan.filename().string() + label},
                      {"voxel", reference.voxel}, {"voxels", grid.morton.size()},
                      {"geometry_bits", geometry}, {"gpcc_geometry_bits", reference.geometry_bits},
                      {"lossless_color_bits", lossless}, {"lossless_total_bits", geometry + lossless},
                      {"draco_lossless_total_bits", draco->bits_per_point},
                      {"issue_draco_lossless_total_bits", reference.issue_draco_lossless_total},
                      {"tile_decode_points_per_second", *tile_rate},
                      {"draco_decode_points_per_second", voxels / draco->decode_seconds},
                      {"whole_process", processes}};
  for (double psnr : {34.0, 38.0, 42.0}) {
    const std::string at = std::to_string(static_cast<int>(psnr));
    r["vbr_color_bits_at_" + at] = BitsAt(curves[ColorCodec::kVariableRate], psnr);
    r["hierarchical_color_bits_at_" + at] = BitsAt(curves[ColorCodec::kHierarchical], psnr);
    r["raht_color_bits_at_" + at] = BitsAt(reference.raht, psnr);
  }
  return r;
}

}  // namespace

int RunVersusBench(const BenchOptions& options) {
  std::vector<nlohmann::json> rows;
  for (const GpccReference& reference : kGpcc) {
    const std::string name = reference.scan;
    const std::filesystem::path scan = std::filesystem::path(options.data_dir) / name;
    if (!std::filesystem::exists(scan)) {
      std::fprintf(stderr, "bench --versus: %s is not in %s, skipped\n", name.c_str(), options.data_dir.c_str());
      continue;
    }
    nlohmann::json r = RunIsolated(name, [&] { return VersusCase(scan, reference); });
    if (options.json) std::cout << r.dump() << std::endl;
    rows.push_back(std::move(r));
  }
  if (options.json) return 0;
  std::printf("machine: %s; ours and Draco (lossless, smallest of all settings) measured now on the same voxels;\n"
              "G-PCC (TMC13 v23 octree + RAHT) as constants measured once on these voxels (docs/benchmarks.md), RAHT\n"
              "interpolated linearly in PSNR-Y between QPs 16..40; VBR and hierarchical between targets 32..44 dB;\n"
              "ours = the smaller of the two (the writer's choice: --color-codec).\n\n",
              MachineName().c_str());
  std::printf("| scan | voxel | voxels | geometry b/vox ours | G-PCC | ours/G-PCC | lossless total ours | Draco | ours/Draco (goal ≤ 0.75) |\n"
              "|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows) {
    if (r.contains("error")) continue;
    const double geometry = r["geometry_bits"], gpcc = r["gpcc_geometry_bits"];
    const double total = r["lossless_total_bits"], draco = r["draco_lossless_total_bits"];
    std::printf("| %s | %g | %zu | %.3f | %.3f | %.2f | %.3f | %.2f | %.3f |\n", r["scan"].get<std::string>().c_str(),
                r["voxel"].get<double>(), r["voxels"].get<size_t>(), geometry, gpcc, geometry / gpcc, total, draco,
                total / draco);
  }
  std::printf("\n| scan | PSNR-Y dB | VBR color b/vox | hierarchical | RAHT | VBR/RAHT | ours/RAHT (goal ≤ 1) | total ours | total G-PCC |"
              " ours/G-PCC (goal ≤ 1) |\n|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows) {
    if (r.contains("error")) {
      std::printf("| %s | error: %s |\n", r.value("scan", "?").c_str(), r["error"].get<std::string>().c_str());
      continue;
    }
    for (const char* at : {"34", "38", "42"}) {
      const double vbr = r[std::string("vbr_color_bits_at_") + at], raht = r[std::string("raht_color_bits_at_") + at];
      const double hierarchical = r[std::string("hierarchical_color_bits_at_") + at];
      const double colors = std::min(vbr, hierarchical);
      const double ours = r["geometry_bits"].get<double>() + colors, theirs = r["gpcc_geometry_bits"].get<double>() + raht;
      std::printf("| %s | %s | %.3f | %.3f | %.3f | %.2f | %.2f | %.3f | %.3f | %.2f |\n", r["case"].get<std::string>().c_str(),
                  at, vbr, hierarchical, raht, vbr / raht, colors / raht, ours, theirs, ours / theirs);
    }
  }
  std::printf("\n| scan | tile decode M points/s ours | Draco decode M points/s | ours/Draco (goal ≥ 2) |\n"
              "|---|---|---|---|\n");
  for (const auto& r : rows) {
    if (r.contains("error")) continue;
    const double ours = r["tile_decode_points_per_second"], draco = r["draco_decode_points_per_second"];
    std::printf("| %s | %.2f | %.2f | %.2f |\n", r["case"].get<std::string>().c_str(), ours / 1e6, draco / 1e6,
                ours / draco);
  }
  std::printf("\n| scan | `pointdag encode --quality 38` s | `--lossless` s | `draco_encoder -cl 10` s | ours 38 dB / Draco (goal ≤ 1) |"
              " `pointdag decode` s | `draco_decoder` s |\n|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows) {
    if (r.contains("error")) continue;
    const nlohmann::json& p = r["whole_process"];
    const double ours = p["encode_38_s"], draco = p.value("draco_encoder_s", NAN);
    std::printf("| %s | %.3f | %.3f | %.3f | %.2f | %.3f | %.3f |\n", r["case"].get<std::string>().c_str(), ours,
                p["encode_lossless_s"].get<double>(), draco, ours / draco, p["decode_38_s"].get<double>(),
                p.value("draco_decoder_s", NAN));
    if (p.contains("draco_missing")) std::printf("%s\n", p["draco_missing"].get<std::string>().c_str());
  }
  std::printf("(whole processes pinned to one core, CPU seconds user + system, best of 3, both reading the voxels from\n"
              "one float32 PLY of voxel indices; ours with POINTDAG_DEVICE=cpu at --voxel 1)\n");
  std::printf("\n| scan | `encode --quality 34 --color-codec hierarchical` s | / draco_encoder | `pointdag decode` of it s |"
              " / draco_decoder |\n|---|---|---|---|---|\n");
  for (const auto& r : rows) {
    if (r.contains("error")) continue;
    const nlohmann::json& p = r["whole_process"];
    const double encode = p["encode_hierarchical_34_s"], decode = p["decode_hierarchical_34_s"];
    std::printf("| %s | %.3f | %.2f | %.3f | %.2f |\n", r["case"].get<std::string>().c_str(), encode,
                encode / p.value("draco_encoder_s", NAN), decode, decode / p.value("draco_decoder_s", NAN));
  }
  for (const auto& r : rows) {
    if (r.contains("error")) std::printf("%s: %s\n", r.value("scan", "?").c_str(), r["error"].get<std::string>().c_str());
  }
  return 0;
}

}  // namespace pointdag
