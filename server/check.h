// The store's integrity check: `pointdagd --data-dir DIR --check` (exit 0 consistent, 1 with the report).
//
// Checks, on a stopped daemon's data folder (uploads being received would count as orphans):
// SQLite's own quick_check; every dataset's metadata is JSON and its tiles are all there
// (tile_count); every tile's bytes match their checksum (XXH3 == ETag) and parse as a .pdag with
// valid CRCs; no tile belongs to no dataset; no file in uploads/ that no queued or running job
// references; every job in a known state, failed ones with a reason, done ones pointing at an
// existing dataset (unless it was deleted since); every shadow set whole (a layer per tile, each
// sound and of its tile's voxel count). Reads only; tiles are read one at a time.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pointdag/status.h"

namespace pointdag::server {

struct CheckReport {
  uint64_t datasets = 0, tiles = 0, jobs = 0, uploads = 0;
  std::vector<std::string> problems;  // one line each, empty when consistent
  bool ok() const { return problems.empty(); }
  std::string ToString() const;  // a summary line, then the problems
};

// An error only when the check itself cannot run (no store, unreadable file).
StatusOr<CheckReport> CheckDataDir(const std::filesystem::path& data_dir);

}  // namespace pointdag::server
