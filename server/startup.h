// What pointdagd does before it serves: tokens from a file or the environment, the rule that an
// open daemon stays on loopback, and the sweep of what a crash left behind.
#pragma once

#include <filesystem>
#include <string>

#include "config.h"
#include "pointdag/status.h"
#include "store.h"

namespace pointdag::server {

// The token's first line, trailing whitespace dropped. Messages never quote the file's content.
StatusOr<std::string> ReadTokenFile(const std::filesystem::path& file);
// Without a write token the daemon listens on loopback only, unless `no_token` says it is meant.
Status CheckExposure(const DaemonConfig& config, bool no_token);
// Removes every file in spill/ (unless `keep_spill`: a job may still be writing there) and every
// upload in uploads/ that no queued or running job uses. Returns how many were removed.
size_t SweepLeftovers(Store& store, const std::filesystem::path& data_dir, bool keep_spill = false);
// Raises the soft limit on open files to the hard one, so max_connections is not cut short by a
// low default.
void RaiseOpenFileLimit();

}  // namespace pointdag::server
