// `pointdag bench --versus`: issue #14's side-by-side table. Ours and Draco measured in this run on
// the same voxels; G-PCC (TMC13 v23, lossless-geometry octree + RAHT) as the constants the issue
// measured on the reference voxelizer's output, for reference (TMC13 is not packaged for Debian).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "bench.h"
#include "pointdag/bench/report.h"
#include "pointdag/compare/draco_compare.h"
#include "pointdag/container/pdag_file.h"
#include "pointdag/pipeline.h"
#include "pointdag/tile/tiler.h"

namespace pointdag {
namespace {

struct RatePoint {
  double psnr_y;
  double bits;
};

struct GpccReference {
  double voxel;
  double geometry_bits;                  // per voxel
  std::pair<RatePoint, RatePoint> raht;  // color bits per voxel at two PSNR-Y
  double draco_lossless_total;           // the Draco figure, for checking ours against
};

const std::map<std::string, GpccReference> kGpcc = {
    {"lion_takanawa_pdrf7_rgb.las", {0.01, 2.98, {{34.0, 1.62}, {39.4, 2.91}}, 21.61}},
    {"pcx_guanyin_cc-by-4.0_rgb.ply", {0.002, 4.93, {{35.6, 1.21}, {40.3, 2.60}}, 20.54}},
    {"autzen_trim_pdrf3_rgb.las", {4.0, 1.73, {{35.6, 0.85}, {40.2, 1.75}}, 18.28}},
};

// Bits at `psnr` on a rate-distortion curve sorted by PSNR: linear between the two points that
// bracket it, extended along the nearest segment outside (RAHT has two points only).
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
  double best = 0;
  for (int pass = 0; pass < 3; ++pass) {
    const auto start = std::chrono::steady_clock::now();
    for (const Tile& tile : tiles.tiles) {
      ASSIGN_OR_RETURN(const PdagFile file, ParsePdag(tile.bytes));
      RETURN_IF_ERROR(DecodePdag(file).status());
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (pass == 0 || seconds < best) best = seconds;
  }
  return points / best;
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
  // VBR at targets bracketing 34..42 dB: the curve is interpolated at exactly 34, 38 and 42.
  std::vector<RatePoint> vbr;
  for (double target : {32.0, 34.0, 36.0, 38.0, 40.0, 42.0, 44.0}) {
    auto colors = EncodeColors(grid.colors, {ColorCodec::kVariableRate, target}, grid.morton);
    if (!colors.ok()) return {{"error", colors.status().ToString()}};
    vbr.push_back({colors->psnr.y, 8.0 * static_cast<double>(colors->bytes.size()) / voxels});
  }
  auto draco = DracoEncodeVoxels(grid);
  if (!draco.ok()) return {{"error", draco.status().ToString()}};
  auto tile_rate = TileDecodeRate(grid);
  if (!tile_rate.ok()) return {{"error", tile_rate.status().ToString()}};
  const std::vector<RatePoint> raht = {reference.raht.first, reference.raht.second};
  nlohmann::json r = {{"scan", scan.filename().string()}, {"voxel", reference.voxel}, {"voxels", grid.morton.size()},
                      {"geometry_bits", geometry}, {"gpcc_geometry_bits", reference.geometry_bits},
                      {"lossless_color_bits", lossless}, {"lossless_total_bits", geometry + lossless},
                      {"draco_lossless_total_bits", draco->bits_per_point},
                      {"issue_draco_lossless_total_bits", reference.draco_lossless_total},
                      {"tile_decode_points_per_second", *tile_rate},
                      {"draco_decode_points_per_second", voxels / draco->decode_seconds}};
  for (double psnr : {34.0, 38.0, 42.0}) {
    const std::string at = std::to_string(static_cast<int>(psnr));
    r["vbr_color_bits_at_" + at] = BitsAt(vbr, psnr);
    r["raht_color_bits_at_" + at] = BitsAt(raht, psnr);
  }
  return r;
}

}  // namespace

int RunVersusBench(const BenchOptions& options) {
  std::vector<nlohmann::json> rows;
  for (const auto& entry : kGpcc) {  // not a structured binding: clang 14 cannot capture one
    const std::string& name = entry.first;
    const GpccReference& reference = entry.second;
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
              "G-PCC (TMC13 v23 octree + RAHT) constants from issue #14, RAHT interpolated linearly in PSNR-Y\n"
              "between its two points (extended beyond them); VBR interpolated between targets 32..44 dB.\n\n",
              MachineName().c_str());
  std::printf("| scan | voxel | voxels | geometry b/vox ours | G-PCC | ours/G-PCC | lossless total ours | Draco | ours/Draco (goal ≤ 0.75) |\n"
              "|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows) {
    if (r.contains("error")) continue;
    const double geometry = r["geometry_bits"], gpcc = r["gpcc_geometry_bits"];
    const double total = r["lossless_total_bits"], draco = r["draco_lossless_total_bits"];
    std::printf("| %s | %g | %zu | %.3f | %.2f | %.2f | %.3f | %.2f | %.3f |\n", r["scan"].get<std::string>().c_str(),
                r["voxel"].get<double>(), r["voxels"].get<size_t>(), geometry, gpcc, geometry / gpcc, total, draco,
                total / draco);
  }
  std::printf("\n| scan | PSNR-Y dB | VBR color b/vox | RAHT | VBR/RAHT (goal ≤ 1) | total ours | total G-PCC | ours/G-PCC (goal ≤ 1) |\n"
              "|---|---|---|---|---|---|---|---|\n");
  for (const auto& r : rows) {
    if (r.contains("error")) {
      std::printf("| %s | error: %s |\n", r.value("scan", "?").c_str(), r["error"].get<std::string>().c_str());
      continue;
    }
    for (const char* at : {"34", "38", "42"}) {
      const double vbr = r[std::string("vbr_color_bits_at_") + at], raht = r[std::string("raht_color_bits_at_") + at];
      const double ours = r["geometry_bits"].get<double>() + vbr, theirs = r["gpcc_geometry_bits"].get<double>() + raht;
      std::printf("| %s | %s | %.3f | %.2f | %.2f | %.3f | %.2f | %.2f |\n", r["scan"].get<std::string>().c_str(), at,
                  vbr, raht, vbr / raht, ours, theirs, ours / theirs);
    }
  }
  std::printf("\n| scan | tile decode M points/s ours | Draco decode M points/s | ours/Draco (goal ≥ 2) |\n"
              "|---|---|---|---|\n");
  for (const auto& r : rows) {
    if (r.contains("error")) continue;
    const double ours = r["tile_decode_points_per_second"], draco = r["draco_decode_points_per_second"];
    std::printf("| %s | %.2f | %.2f | %.2f |\n", r["scan"].get<std::string>().c_str(), ours / 1e6, draco / 1e6,
                ours / draco);
  }
  for (const auto& r : rows) {
    if (r.contains("error")) std::printf("%s: %s\n", r.value("scan", "?").c_str(), r["error"].get<std::string>().c_str());
  }
  return 0;
}

}  // namespace pointdag
