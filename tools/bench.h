// `pointdag bench`: the codec-core benchmark over a folder of scans (a command, not a test).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace pointdag {

struct BenchOptions {
  std::string data_dir = "../shared/data";
  bool json = false;
  bool colors = false;  // the color codecs' rate-distortion table and decoding speed instead
  bool ingest = false;  // the daemon's pipeline per scan: stage times, points/s, peak RSS
  bool devices = false;  // each stage with Vulkan kernels, CPU path vs Vulkan path
  bool laz = false;      // LAZ decoding (data_dir/laz): points/s on one core and all, LAZ vs LAS ingest
  bool versus = false;   // issue #14: ours, Draco and G-PCC side by side (sizes at equal PSNR-Y)
  std::string server;    // a running pointdagd's URL: each scan uploaded to it, end to end (tools/upload_bench.cc)
  uint64_t max_points_in_memory = uint64_t{1} << 25;
  // The nightly benchmark (issue #15): a corpus (TOML or folder), the report folder, a baseline
  // report (default: the newest in out_dir), the tolerances, and how many reports to keep (0: all).
  std::string corpus, out_dir, baseline;
  double size_tolerance = 0.005, psnr_tolerance = 0.05;
  size_t keep_reports = 0;
};

int RunBench(const BenchOptions& options);
int RunLazBench(const BenchOptions& options);  // tools/laz_bench.cc
int RunVersusBench(const BenchOptions& options);  // tools/versus_bench.cc
int RunCorpusBench(const BenchOptions& options);  // tools/corpus_bench.cc
int RunUploadBench(const BenchOptions& options);  // tools/upload_bench.cc

// Shared by the benchmarks.
// The scans (.las, .ply, .pcd) in `dir`, sorted by name.
std::vector<std::filesystem::path> ScansIn(const std::string& dir);
// The CRS a shared scan must be read in because the one it stores is wrong (lone_star's), if any.
std::optional<int> CrsOverride(const std::string& scan_name);
// Resident set size now and its high-water mark, in bytes (from /proc/self/status).
std::pair<uint64_t, uint64_t> RssAndPeak();
// Runs one case in a forked child, so each case's peak RSS is its own; its JSON comes back.
nlohmann::json RunIsolated(const std::string& scan_name, const std::function<nlohmann::json()>& run_case);
// IngestScan as pointdagd runs it on one scan: stage times, points/s, sizes, peak RSS.
nlohmann::json RunIngestCase(const std::filesystem::path& scan, uint64_t max_points_in_memory);

}  // namespace pointdag
