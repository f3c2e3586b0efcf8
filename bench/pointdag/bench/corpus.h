// The nightly benchmark's corpus: which scans, at which voxel sizes and quality targets.
//
// Either a folder (every scan directly in it, recognised by content as OpenScan does; other files
// are skipped; each at the voxel size derived from its point spacing, as pointdagd derives it, in
// the scan's own units) or a TOML file:
//
//   targets = [34.0, 38.0, 42.0]   # PSNR-Y targets of the lossy codecs (this is the default)
//   [[scan]]
//   file = "lion.las"              # relative to the corpus file's folder, or absolute
//   voxel = 0.01                   # optional: derived from point spacing when left out
//   targets = [38.0]               # optional: this scan's own targets
//
// Errors: kNotFound for a missing corpus or scan, kInvalidArgument for a malformed TOML file or a
// value out of range (voxel <= 0, a target outside 10..99 dB), naming the file and the key.
#pragma once

#include <filesystem>
#include <vector>

#include "pointdag/status.h"

namespace pointdag {

struct CorpusCase {
  std::filesystem::path scan;
  double voxel = 0;
  bool voxel_derived = false;
  std::vector<double> targets;
};

inline const std::vector<double> kDefaultCorpusTargets = {34.0, 38.0, 42.0};

StatusOr<std::vector<CorpusCase>> LoadCorpus(const std::filesystem::path& corpus);

}  // namespace pointdag
