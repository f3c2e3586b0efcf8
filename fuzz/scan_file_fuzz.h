// Shared body of the scan reader targets (las, ply, pcd): OpenScan takes a path, so each input is
// written to one scratch file per process, opened, read to the end batch by batch, and surveyed.
// Statuses are ignored: the target fails only on a crash, a sanitizer report, an allocation above
// libFuzzer's -malloc_limit_mb or a hang.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "pointdag/read/pcl_reader.h"
#include "pointdag/read/scan_reader.h"

namespace pointdag::fuzz {

inline const std::filesystem::path& ScratchFile(const char* target) {
  static const std::filesystem::path path = [target] {
    const char* tmp = std::getenv("TMPDIR");
    auto p = std::filesystem::path(tmp && *tmp ? tmp : "/tmp") /
             ("pointdag-fuzz-" + std::string(target) + "-" + std::to_string(::getpid()));
    std::atexit([] { std::error_code ec; std::filesystem::remove(ScratchFile(nullptr), ec); });
    return p;
  }();
  return path;
}

// PCL's reader is a module loaded on first use (pcl_reader.h). The PLY and PCD targets load it from
// LLVMFuzzerInitialize, before libFuzzer starts, so that its coverage counts from the first input
// (opening a missing file loads the module, then fails).
inline void LoadPclReader() { (void)OpenPclScan("/nonexistent/pointdag-fuzz.pcd", ScanFormat::kPcd); }

inline int FuzzScanFile(const char* target, const uint8_t* data, size_t size) {
  const std::filesystem::path& path = ScratchFile(target);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();  // the harness itself is broken: say so loudly
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  auto reader = OpenScan(path);
  if (!reader.ok()) return 0;
  PointBatch batch;
  for (;;) {
    auto n = (*reader)->Read(batch, 4096);
    if (!n.ok() || *n == 0) break;
  }
  (void)SurveyScan(**reader, 4096);
  return 0;
}

}  // namespace pointdag::fuzz
