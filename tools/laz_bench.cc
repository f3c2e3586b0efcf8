// `pointdag bench --laz`: our LAZ decoder on every .laz in DATA/laz (and DATA): points/s on one
// core and on all cores, best of three; then the daemon's whole ingest of each large LAZ against
// the same records stored as plain LAS (written here, beside the LAZ in a temporary folder).
// laz-perf's rate on the same files comes from web/bench/laz_perf_bench.mjs (scripts/bench-laz).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include <tbb/task_arena.h>

#include "bench.h"
#include "pointdag/bench/report.h"
#include "pointdag/read/byte_io.h"
#include "pointdag/read/laz/laz_reader.h"

namespace pointdag {
namespace {

std::vector<std::filesystem::path> LazFilesIn(const std::string& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& folder : {std::filesystem::path(dir) / "laz", std::filesystem::path(dir)}) {
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
      if (entry.path().extension() == ".laz") files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Seconds to decode every record, best of three, inside `arena` (one thread, or all).
StatusOr<double> TimeDecode(const std::filesystem::path& file, tbb::task_arena& arena) {
  double best = 1e30;
  for (int run = 0; run < 3; ++run) {
    Status status;
    const auto start = std::chrono::steady_clock::now();
    arena.execute([&] {
      auto reader = laz::LazReader::Open(file);
      if (!reader.ok()) {
        status = reader.status();
        return;
      }
      std::vector<uint8_t> records;
      for (;;) {
        records.clear();
        auto n = (*reader)->ReadRecords(records, 1 << 16);
        if (!n.ok() || *n == 0) {
          status = n.status();
          return;
        }
      }
    });
    RETURN_IF_ERROR(status);
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return best;
}

nlohmann::json DecodeCase(const std::filesystem::path& file) {
  nlohmann::json r = {{"file", file.filename().string()}};
  auto reader = laz::LazReader::Open(file);
  if (!reader.ok()) {
    r["error"] = reader.status().ToString();
    return r;
  }
  r["points"] = (*reader)->info().point_count;
  r["point_format"] = (*reader)->info().las_point_format;
  r["compression"] = (*reader)->info().compression;
  tbb::task_arena one(1), all;
  const auto one_s = TimeDecode(file, one);
  const auto all_s = TimeDecode(file, all);
  if (!one_s.ok() || !all_s.ok()) {
    r["error"] = (one_s.ok() ? all_s.status() : one_s.status()).ToString();
    return r;
  }
  const double points = r["points"].get<double>();
  r["one_core_points_per_s"] = points / *one_s;
  r["all_cores_points_per_s"] = points / *all_s;
  r["threads"] = all.max_concurrency();
  return r;
}

// The LAZ's records as a plain LAS: its header and VLRs with the compression bit cleared (and no
// EVLRs), then the decompressed records.
Status WriteDecompressedLas(const std::filesystem::path& laz, const std::filesystem::path& las) {
  ASSIGN_OR_RETURN(const std::vector<uint8_t> records, laz::DecodeAllRecords(laz));
  std::ifstream in(laz, std::ios::binary);
  std::vector<uint8_t> head(375);
  in.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  const uint32_t data_offset = LoadLE<uint32_t>(head.data() + 96);
  head.resize(data_offset);
  in.seekg(0);
  in.read(reinterpret_cast<char*>(head.data()), data_offset);
  head[104] &= 0x3F;
  if (head[25] >= 4) std::fill(head.begin() + 235, head.begin() + 247, uint8_t{0});  // no EVLRs
  std::ofstream out(las, std::ios::binary);
  out.write(reinterpret_cast<const char*>(head.data()), static_cast<std::streamsize>(head.size()));
  out.write(reinterpret_cast<const char*>(records.data()), static_cast<std::streamsize>(records.size()));
  return out ? Status::Ok() : IoError("cannot write " + las.string());
}

}  // namespace

int RunLazBench(const BenchOptions& options) {
  const auto files = LazFilesIn(options.data_dir);
  if (!options.json) {
    std::printf("machine: %s; LAZ decoding to records, best of 3\n", MachineName().c_str());
    std::printf("| file | PDRF | points | compression | Mpt/s 1 core | Mpt/s all cores |\n|---|---|---|---|---|---|\n");
  }
  for (const auto& file : files) {
    const nlohmann::json r = DecodeCase(file);
    if (options.json) {
      std::cout << r.dump() << std::endl;
    } else if (r.contains("error")) {
      std::printf("| %s | refused: %s |\n", file.filename().c_str(), r["error"].get<std::string>().c_str());
    } else {
      std::printf("| %s | %d | %llu | %s | %.2f | %.2f (%d threads) |\n", file.filename().c_str(),
                  r["point_format"].get<int>(), r["points"].get<unsigned long long>(),
                  r["compression"].get<std::string>().c_str(), r["one_core_points_per_s"].get<double>() / 1e6,
                  r["all_cores_points_per_s"].get<double>() / 1e6, r["threads"].get<int>());
    }
    std::fflush(stdout);
  }
  // Whole ingests of the large files, LAZ against the same records as LAS.
  const auto scratch = std::filesystem::temp_directory_path() / ("pointdag-laz-bench-" + std::to_string(getpid()));
  std::filesystem::create_directories(scratch);
  if (!options.json) {
    std::printf("\nIngest (IngestScan as pointdagd runs it), LAZ vs the same records as LAS:\n"
                "| file | points | LAZ total s | LAZ Mpt/s | LAS total s | LAS Mpt/s | same voxels |\n|---|---|---|---|---|---|---|\n");
  }
  for (const auto& file : files) {
    auto reader = laz::LazReader::Open(file);
    if (!reader.ok() || (*reader)->info().point_count < 100000) continue;
    const auto las = scratch / (file.stem().string() + ".las");
    if (const Status s = WriteDecompressedLas(file, las); !s.ok()) continue;
    const nlohmann::json a = RunIsolated(file.filename().string(), [&] { return RunIngestCase(file, options.max_points_in_memory); });
    const nlohmann::json b = RunIsolated(las.filename().string(), [&] { return RunIngestCase(las, options.max_points_in_memory); });
    std::filesystem::remove(las);
    if (options.json) {
      std::cout << nlohmann::json{{"file", file.filename().string()}, {"laz", a}, {"las", b}}.dump() << std::endl;
      continue;
    }
    if (a.contains("error") || b.contains("error")) {
      std::printf("| %s | error: %s |\n", file.filename().c_str(), (a.contains("error") ? a : b)["error"].dump().c_str());
      continue;
    }
    std::printf("| %s | %llu | %.2f | %.2f | %.2f | %.2f | %s |\n", file.filename().c_str(),
                a["points"].get<unsigned long long>(), a["total_s"].get<double>(), a["points_per_s"].get<double>() / 1e6,
                b["total_s"].get<double>(), b["points_per_s"].get<double>() / 1e6,
                a["voxels"] == b["voxels"] && a["finest_bits_per_voxel"] == b["finest_bits_per_voxel"] ? "yes" : "NO");
    std::fflush(stdout);
  }
  std::filesystem::remove_all(scratch);
  return 0;
}

}  // namespace pointdag
