#include "bench.h"

#include <malloc.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <vector>

#include "pointdag/bench/report.h"
#include "pointdag/color/block_codec.h"
#include "pointdag/compare/draco_compare.h"
#include "pointdag/compare/scorecard.h"
#include "pointdag/gpu/stage_device.h"
#include "pointdag/ingest.h"
#include "pointdag/pipeline.h"

namespace pointdag {
namespace {

// Two voxel sizes per known scan (in the scan's own units), the first as in ARCHITECTURE.md's table.
const std::map<std::string, std::pair<double, double>> kVoxelSizes = {
    {"lion_takanawa_pdrf7_rgb.las", {0.01, 0.005}},
    {"autzen_trim_pdrf3_rgb.las", {4.0, 2.0}},
    {"autzen_trim_las14_pdrf7_rgb.las", {4.0, 2.0}},
    {"pcx_guanyin_cc-by-4.0_rgb.ply", {0.002, 0.001}},
    {"ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las", {0.5, 0.25}},
    {"pcl_milk_cartoon_clorox_kinect_rgb.ply", {0.004, 0.002}},
    {"lone_star_tls_noRGB.las", {0.05, 0.02}},
    {"tiny_1.2-with-color_1065pts.las", {8.0, 4.0}},
};

}  // namespace

std::pair<uint64_t, uint64_t> RssAndPeak() {
  std::ifstream status("/proc/self/status");
  std::string key;
  uint64_t rss = 0, peak = 0;
  while (status >> key) {
    uint64_t kb = 0;
    if (key == "VmRSS:" && status >> kb) rss = kb * 1024;
    if (key == "VmHWM:" && status >> kb) peak = kb * 1024;
  }
  return {rss, peak};
}

namespace {

nlohmann::json RunCase(const std::filesystem::path& scan, double voxel, uint64_t max_points_in_memory) {
  // Warm up on the same file at the coarsest grid so that code pages are in, give the heap back,
  // then reset the high-water mark: what remains is the memory this case itself needs.
  EncodeOptions warm;
  warm.depth = 2;
  (void)EncodeScan(scan, warm);
  RetainFreedMemory();  // as pointdagd
  malloc_trim(0);
  std::ofstream("/proc/self/clear_refs") << "5";
  const uint64_t baseline = RssAndPeak().first;
  EncodeOptions options;
  options.voxel_size = voxel;
  options.max_points_in_memory = max_points_in_memory;
  auto encoded = EncodeScan(scan, options);
  if (!encoded.ok()) return {{"error", encoded.status().ToString()}};
  const uint64_t peak = RssAndPeak().second;
  // Timings: best of three runs, the usual guard against a busy shared machine.
  for (int repeat = 0; repeat < 2; ++repeat) {
    auto again = EncodeScan(scan, options);
    if (!again.ok()) break;
    encoded->seconds.read_voxelize = std::min(encoded->seconds.read_voxelize, again->seconds.read_voxelize);
    encoded->seconds.build = std::min(encoded->seconds.build, again->seconds.build);
  }
  auto zstd_stream = EncodeDag(encoded->dag, GeometryCoder::kZstd);
  auto draco = DracoEncodeVoxels(encoded->grid);
  const double points = static_cast<double>(encoded->grid.points_in);
  const double voxels = static_cast<double>(encoded->grid.morton.size());
  const auto bpv = [&](size_t bytes) { return 8.0 * static_cast<double>(bytes) / voxels; };
  const auto& s = encoded->seconds;
  return {
      {"scan", scan.filename().string()},
      {"voxel", voxel},
      {"points", encoded->grid.points_in},
      {"voxels", encoded->grid.morton.size()},
      {"depth", encoded->grid.depth},
      {"chunk_levels", encoded->grid.chunk_levels},
      {"read_voxelize_points_per_s", points / s.read_voxelize},
      {"build_points_per_s", points / s.build},
      {"read_voxelize_build_points_per_s", points / (s.read_voxelize + s.build)},
      {"peak_rss_bytes", peak},
      {"peak_rss_over_baseline_bytes", peak - baseline},
      {"raw_point_bytes", std::filesystem::file_size(scan)},
      {"resident_bits_per_voxel", bpv(encoded->dag.ResidentBytes())},
      {"stored_zstd_bits_per_voxel", zstd_stream.ok() ? bpv(zstd_stream->size()) : -1.0},
      {"stored_context_bits_per_voxel", bpv(encoded->file.geometry.size())},
      {"draco_bits_per_point", draco.ok() ? draco->bits_per_point : -1.0},
  };
}

}  // namespace

// Each case runs in its own child process so that peak RSS is that case's alone.
nlohmann::json RunIsolated(const std::string& scan_name, const std::function<nlohmann::json()>& run_case) {
  int fds[2];
  if (pipe(fds) != 0) return {{"error", "pipe failed"}};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    const std::string line = run_case().dump();
    [[maybe_unused]] const ssize_t n = write(fds[1], line.data(), line.size());
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  std::string text;
  char buf[4096];
  for (ssize_t n; (n = read(fds[0], buf, sizeof(buf))) > 0;) text.append(buf, static_cast<size_t>(n));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  auto result = nlohmann::json::parse(text, nullptr, false);
  if (result.is_discarded()) return {{"scan", scan_name}, {"error", "benchmark child crashed"}};
  return result;
}

namespace {

// Random single-color lookups and whole-array decoding of the VBR codec at 38 dB, one core; the
// colors one per voxel in Morton order (`morton`), as a file stores them.
nlohmann::json MeasureColorDecoding(const std::vector<Rgb8>& colors, std::span<const uint64_t> morton) {
  auto encoded = EncodeColors(colors, {ColorCodec::kVariableRate, 38.0}, morton);
  if (!encoded.ok()) return {{"error", encoded.status().ToString()}};
  double best_open = 1e30;
  for (int repeat = 0; repeat < 3; ++repeat) {
    const auto start = std::chrono::steady_clock::now();
    auto opened = BlockColorDecoder::Open(std::span(encoded->bytes).subspan(1), colors.size(), morton);
    best_open = std::min(best_open, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (!opened.ok()) return {{"error", opened.status().ToString()}};
  }
  auto decoder = BlockColorDecoder::Open(std::span(encoded->bytes).subspan(1), colors.size(), morton);
  if (!decoder.ok()) return {{"error", decoder.status().ToString()}};
  std::mt19937_64 rng(1);
  std::vector<uint64_t> indices(1 << 22);
  for (auto& i : indices) i = rng() % colors.size();
  uint32_t sink = 0;
  double best_lookup = 1e30, best_batch = 1e30;
  for (int repeat = 0; repeat < 3; ++repeat) {
    auto start = std::chrono::steady_clock::now();
    for (uint64_t i : indices) sink += decoder->At(i).g;
    best_lookup = std::min(best_lookup, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    start = std::chrono::steady_clock::now();
    sink += decoder->DecodeAll().back().r;
    best_batch = std::min(best_batch, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return {{"lookups_per_s", static_cast<double>(indices.size()) / best_lookup},
          {"batch_colors_per_s", static_cast<double>(colors.size()) / best_batch},
          {"open_colors_per_s", static_cast<double>(colors.size()) / best_open},
          {"blocks", decoder->block_count()},
          {"checksum", sink}};
}

}  // namespace

std::vector<std::filesystem::path> ScansIn(const std::string& dir) {
  std::vector<std::filesystem::path> scans;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const auto ext = entry.path().extension().string();
    if (ext == ".las" || ext == ".ply" || ext == ".pcd") scans.push_back(entry.path());
  }
  std::sort(scans.begin(), scans.end());
  return scans;
}

std::optional<int> CrsOverride(const std::string& scan_name) {
  // Lone Star's stored CRS is wrong, in its LAS and in its LAZ/COPC copies alike (UTM 12N is right).
  if (scan_name.find("lone_star") != std::string::npos || scan_name.find("lone-star") != std::string::npos) return 26912;
  return std::nullopt;
}

// The daemon's pipeline (read, georeference, voxelize, tile, Draco) on one scan at its derived voxel
// size, twice in this process: the first as a freshly started daemon's first upload (PROJ resolves
// the CRS, the allocator and page cache are cold), the second as a running daemon ingests (the
// stage times, total and points/s are the second's; "first_total_s" is the first's).
nlohmann::json RunIngestCase(const std::filesystem::path& scan, uint64_t max_points_in_memory) {
  RetainFreedMemory();  // as pointdagd
  malloc_trim(0);
  std::ofstream("/proc/self/clear_refs") << "5";
  const uint64_t baseline = RssAndPeak().first;
  IngestOptions options;
  options.max_points_in_memory = max_points_in_memory;
  options.epsg = CrsOverride(scan.filename().string());
  double first_seconds = 0;
  {  // freed before the second run
    auto first = IngestScan(scan, options);
    if (!first.ok()) return {{"scan", scan.filename().string()}, {"error", first.status().ToString()}};
    first_seconds = first->seconds;
  }
  auto ingested = IngestScan(scan, options);
  if (!ingested.ok()) return {{"scan", scan.filename().string()}, {"error", ingested.status().ToString()}};
  const uint64_t peak = RssAndPeak().second;
  const double points = static_cast<double>(ingested->grid.points_in);
  uint64_t finest_bytes = 0;
  // FNV-1a over every tile's bytes in key order: equal digests, equal datasets (for checking that a
  // speed change changed no byte).
  uint64_t digest = 0xcbf29ce484222325;
  for (const Tile& t : ingested->tiles.tiles) {
    if (t.key.level == ingested->tiles.levels - 1) finest_bytes += t.bytes.size();
    for (uint8_t b : t.bytes) digest = (digest ^ b) * 0x100000001b3;
  }
  char tiles_digest[17];
  std::snprintf(tiles_digest, sizeof(tiles_digest), "%016llx", static_cast<unsigned long long>(digest));
  const double finest_bpv = 8.0 * static_cast<double>(finest_bytes) / static_cast<double>(ingested->grid.morton.size());
  return {{"scan", scan.filename().string()},
          {"points", ingested->grid.points_in},
          {"georeferenced", ingested->frame.georeferenced},
          {"voxel", ingested->grid.voxel_size},
          {"voxels", ingested->grid.morton.size()},
          {"levels", ingested->tiles.levels},
          {"tiles", ingested->tiles.tiles.size()},
          {"tiles_fnv1a", tiles_digest},
          {"all_levels_bits_per_point", 8.0 * static_cast<double>(ingested->tiles.stored_bytes()) / points},
          {"finest_bits_per_voxel", finest_bpv},
          {"draco_bits_per_point", ingested->draco.bits_per_point},
          {"voxelize_s", ingested->voxelize_seconds},
          {"tile_s", ingested->tile_seconds},
          {"draco_s", ingested->compare_seconds},
          {"first_total_s", first_seconds},
          {"total_s", ingested->seconds},
          {"points_per_s", points / ingested->seconds},
          {"peak_rss_over_baseline_bytes", peak - baseline}};
}

namespace {

int RunIngestBench(const BenchOptions& options) {
  if (!options.json) {
    std::printf("machine: %s; IngestScan as pointdagd runs it (derived voxel, VBR tiles at 38 dB, Draco kd-tree level 10),\n"
                "twice per scan in one process: stage times, total and Mpt/s of the second (a running daemon), first upload s\n"
                "of the first (a freshly started one)\n",
                MachineName().c_str());
    std::printf("| scan | points | ENU | voxel | voxels | levels | tiles | all levels b/pt | finest b/vox | Draco b/pt | "
                "voxelize s | tile s | Draco s | total s | Mpt/s | first upload s | peak RSS MiB (net) |\n|");
    for (int i = 0; i < 17; ++i) std::printf("---|");
    std::printf("\n");
  }
  for (const auto& scan : ScansIn(options.data_dir)) {
    const nlohmann::json r = RunIsolated(scan.filename().string(), [&] { return RunIngestCase(scan, options.max_points_in_memory); });
    if (options.json) {
      std::cout << r.dump() << std::endl;
      continue;
    }
    if (r.contains("error")) {
      std::printf("| %s | error: %s |\n", scan.filename().c_str(), r["error"].get<std::string>().c_str());
      continue;
    }
    std::printf("| %s | %llu | %s | %g | %llu | %d | %llu | %.2f | %.2f | %.2f | %.3f | %.3f | %.3f | %.3f | %.2f | %.3f | %.1f |\n",
                scan.filename().c_str(), r["points"].get<unsigned long long>(), r["georeferenced"].get<bool>() ? "yes" : "no",
                r["voxel"].get<double>(), r["voxels"].get<unsigned long long>(), r["levels"].get<int>(),
                r["tiles"].get<unsigned long long>(), r["all_levels_bits_per_point"].get<double>(),
                r["finest_bits_per_voxel"].get<double>(), r["draco_bits_per_point"].get<double>(), r["voxelize_s"].get<double>(),
                r["tile_s"].get<double>(), r["draco_s"].get<double>(), r["total_s"].get<double>(),
                r["points_per_s"].get<double>() / 1e6, r["first_total_s"].get<double>(), r["peak_rss_over_baseline_bytes"].get<double>() / (1024.0 * 1024.0));
    std::fflush(stdout);
  }
  return 0;
}

// Rate-distortion of every color codec, and decoding speed, at each scan's first voxel size.
int RunColorBench(const BenchOptions& options) {
  if (!options.json) {
    std::printf("machine: %s; color encoders use both cores (oneTBB over macro blocks), decoding one core\n",
                MachineName().c_str());
    std::printf("| scan | voxel | voxels | codec | target dB | PSNR-Y dB | PSNR-Y vs original dB | color b/vox | geometry b/vox | total b/vox | Draco b/pt | Draco / ours |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  }
  std::vector<std::string> speed_rows;
  for (const auto& scan : ScansIn(options.data_dir)) {
    const auto it = kVoxelSizes.find(scan.filename().string());
    if (it == kVoxelSizes.end()) continue;
    EncodeOptions encode;
    encode.voxel_size = it->second.first;
    auto encoded = EncodeScan(scan, encode);
    if (!encoded.ok() || !encoded->grid.has_color()) continue;
    auto card = BuildScorecard(*encoded);
    if (!card.ok()) continue;
    const nlohmann::json speed = MeasureColorDecoding(encoded->grid.colors, encoded->grid.morton);
    if (options.json) {
      std::cout << nlohmann::json{{"scan", scan.filename().string()}, {"voxel", encode.voxel_size.value()},
                                  {"scorecard", *card}, {"decoding", speed}}.dump()
                << std::endl;
      continue;
    }
    const auto decibels = [](const nlohmann::json& v) { return v.is_null() ? std::string("exact") : std::to_string(v.get<double>()).substr(0, 5); };
    for (const auto& c : (*card)["codecs"]) {
      const std::string name = c["name"].get<std::string>() + (c["curve"].is_null() ? "" : "/" + c["curve"].get<std::string>());
      std::printf("| %s | %g | %zu | %s | %s | %s | %s | %.3f | %.3f | %.3f | %.2f | %.2fx |\n", scan.filename().c_str(),
                  encode.voxel_size.value(), encoded->grid.morton.size(), name.c_str(),
                  c["target_psnr"].is_null() ? "-" : std::to_string(c["target_psnr"].get<int>()).c_str(),
                  decibels(c["psnr_y"]).c_str(), decibels(c["psnr_y_vs_original"]).c_str(),
                  c["color_bits_per_voxel"].get<double>(), (*card)["geometry_bits_per_voxel"].get<double>(),
                  c["total_bits_per_voxel"].get<double>(), (*card)["draco_bits_per_point"].get<double>(),
                  c["draco_over_ours"].get<double>());
    }
    std::fflush(stdout);
    if (!speed.contains("error")) {
      char row[256];
      std::snprintf(row, sizeof(row), "| %s | %zu | %.1f | %.1f | %.1f |", scan.filename().c_str(), speed["blocks"].get<size_t>(),
                    speed["lookups_per_s"].get<double>() / 1e6, speed["batch_colors_per_s"].get<double>() / 1e6,
                    speed["open_colors_per_s"].get<double>() / 1e6);
      speed_rows.push_back(row);
    }
  }
  if (!options.json) {
    std::printf("\nVBR at 38 dB, decoding on one core (best of 3):\n");
    std::printf("| scan | blocks | random lookups M/s | batch decode M colors/s | open M colors/s |\n|---|---|---|---|---|\n");
    for (const auto& row : speed_rows) std::printf("%s\n", row.c_str());
  }
  return 0;
}

// One scan with every stage on `device` (POINTDAG_DEVICE=cpu or vulkan), after a warm-up run that
// builds the Vulkan pipelines: read+voxelize (the sort and reduction run on the device) and the VBR
// block encoder at max MSE 16, best of 3.
nlohmann::json RunDeviceCase(const std::filesystem::path& scan, double voxel, const char* device) {
  setenv("POINTDAG_DEVICE", device, 1);
  gpu::ResetProcessDevice();
  if (const Status s = ChooseStageDevices(); !s.ok()) return {{"error", s.ToString()}};
  EncodeOptions options;
  options.voxel_size = voxel;
  options.colors = {ColorCodec::kLossless, std::nullopt};
  auto encoded = EncodeScan(scan, options);
  if (!encoded.ok()) return {{"error", encoded.status().ToString()}};
  using Clock = std::chrono::steady_clock;
  double voxelize_s = 1e30, build_s = 1e30, blocks_s = 1e30;
  for (int repeat = 0; repeat < 3; ++repeat) {
    auto again = EncodeScan(scan, options);
    if (!again.ok()) return {{"error", again.status().ToString()}};
    voxelize_s = std::min(voxelize_s, again->seconds.read_voxelize);
    build_s = std::min(build_s, again->seconds.build);
    if (!encoded->grid.has_color()) continue;
    const auto start = Clock::now();
    if (auto blocks = EncodeBlocks(encoded->grid.colors, BlockLayout::kVariableRate, 16.0); !blocks.ok()) {
      return {{"error", blocks.status().ToString()}};
    }
    blocks_s = std::min(blocks_s, std::chrono::duration<double>(Clock::now() - start).count());
  }
  auto vulkan = gpu::ProcessDevice();
  return {{"scan", scan.filename().string()},
          {"device", vulkan.ok() && *vulkan ? (*vulkan)->device_name() : "cpu"},
          {"points", encoded->grid.points_in},
          {"voxels", encoded->grid.morton.size()},
          {"read_voxelize_s", voxelize_s},
          {"build_s", build_s},
          {"color_blocks_s", encoded->grid.has_color() ? nlohmann::json(blocks_s) : nlohmann::json()}};
}

int RunDeviceBench(const BenchOptions& options) {
  if (!options.json) {
    std::printf("machine: %s; read+voxelize (sort and reduction on the path named), DAG build (subtree hashes on the path named) "
                "and the VBR block encoder (max MSE 16), best of 3\n",
                MachineName().c_str());
    std::printf("| scan | voxel | points | voxels | read+voxelize CPU Mpt/s | on Vulkan Mpt/s | DAG build CPU Mpt/s | on Vulkan Mpt/s | "
                "VBR blocks CPU M colors/s | on Vulkan M colors/s | Vulkan device |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  }
  for (const auto& scan : ScansIn(options.data_dir)) {
    const auto it = kVoxelSizes.find(scan.filename().string());
    if (it == kVoxelSizes.end()) continue;
    const double voxel = it->second.first;
    const nlohmann::json cpu = RunIsolated(scan.filename().string(), [&] { return RunDeviceCase(scan, voxel, "cpu"); });
    const nlohmann::json vulkan = RunIsolated(scan.filename().string(), [&] { return RunDeviceCase(scan, voxel, "vulkan"); });
    if (options.json) {
      std::cout << nlohmann::json{{"cpu", cpu}, {"vulkan", vulkan}}.dump() << std::endl;
      continue;
    }
    if (cpu.contains("error") || vulkan.contains("error")) {
      std::printf("| %s | %g | error: %s |\n", scan.filename().c_str(), voxel, (cpu.contains("error") ? cpu : vulkan)["error"].dump().c_str());
      continue;
    }
    const double points = cpu["points"].get<double>(), voxels = cpu["voxels"].get<double>();
    const auto rate = [](const nlohmann::json& seconds, double n) {
      return seconds.is_null() ? std::string("-") : std::to_string(n / seconds.get<double>() / 1e6).substr(0, 5);
    };
    std::printf("| %s | %g | %.0f | %.0f | %s | %s | %s | %s | %s | %s | %s |\n", scan.filename().c_str(), voxel, points, voxels,
                rate(cpu["read_voxelize_s"], points).c_str(), rate(vulkan["read_voxelize_s"], points).c_str(),
                rate(cpu["build_s"], points).c_str(), rate(vulkan["build_s"], points).c_str(),
                rate(cpu["color_blocks_s"], voxels).c_str(), rate(vulkan["color_blocks_s"], voxels).c_str(),
                vulkan["device"].get<std::string>().c_str());
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int RunBench(const BenchOptions& options) {
  if (options.colors) return RunColorBench(options);
  if (options.devices) return RunDeviceBench(options);
  if (options.laz) return RunLazBench(options);
  if (!options.corpus.empty()) return RunCorpusBench(options);
  if (options.versus) return RunVersusBench(options);
  if (options.ingest) return RunIngestBench(options);
  if (!options.server.empty()) return RunUploadBench(options);
  const auto scans = ScansIn(options.data_dir);
  if (!options.json) {
    std::printf("machine: %s; one core (the codec core is single-threaded); times are the best of 3 runs\n",
                MachineName().c_str());
    std::printf("| scan | voxel | points | voxels | read+vox Mpt/s | build Mpt/s | read+vox+build Mpt/s | peak RSS MiB (net) | raw MiB "
                "| resident b/vox | stored zstd b/vox | stored ctx b/vox | Draco b/pt |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  }
  for (const auto& scan : scans) {
    const auto it = kVoxelSizes.find(scan.filename().string());
    if (it == kVoxelSizes.end()) continue;
    for (double voxel : {it->second.first, it->second.second}) {
      const nlohmann::json r =
          RunIsolated(scan.filename().string(), [&] { return RunCase(scan, voxel, options.max_points_in_memory); });
      if (options.json) {
        std::cout << r.dump() << std::endl;
        continue;
      }
      if (r.contains("error")) {
        std::printf("| %s | %g | error: %s |\n", scan.filename().c_str(), voxel, r["error"].get<std::string>().c_str());
        continue;
      }
      const auto mib = [](const nlohmann::json& v) { return v.get<double>() / (1024.0 * 1024.0); };
      std::printf("| %s | %g | %llu | %llu | %.2f | %.2f | %.2f | %.1f (%.1f) | %.1f | %.2f | %.3f | %.3f | %.2f |\n",
                  scan.filename().c_str(), voxel, r["points"].get<unsigned long long>(),
                  r["voxels"].get<unsigned long long>(), r["read_voxelize_points_per_s"].get<double>() / 1e6,
                  r["build_points_per_s"].get<double>() / 1e6, r["read_voxelize_build_points_per_s"].get<double>() / 1e6,
                  mib(r["peak_rss_bytes"]), mib(r["peak_rss_over_baseline_bytes"]), mib(r["raw_point_bytes"]),
                  r["resident_bits_per_voxel"].get<double>(), r["stored_zstd_bits_per_voxel"].get<double>(),
                  r["stored_context_bits_per_voxel"].get<double>(), r["draco_bits_per_point"].get<double>());
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace pointdag
