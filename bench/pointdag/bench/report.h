// The nightly benchmark's report (report.json; schema in docs/nightly.md) and its comparison with
// a baseline report.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "pointdag/status.h"

namespace pointdag {

// The CPU in words ("AMD EPYC 7B13, 2 cores, Linux x86_64").
std::string MachineName();

// This build's version (`git describe` when it was configured) and libdraco's.
std::string PointdagVersion();
std::string DracoVersion();

// A report around `cases` (RunCorpusCase's results): id (UTC time, "20261123T170501Z"), creation
// time, machine, versions and the exact settings the run used.
nlohmann::json MakeReport(std::vector<nlohmann::json> cases, const std::string& corpus, const nlohmann::json& settings);

// What counts as worse: a size (bits per point, geometry bits per voxel) larger by more than
// `size_growth` (relative), or a quality (PSNR-Y at the same target) lower by more than `psnr_drop` dB.
// The PSNR search lands within a few hundredths of a dB of its target, so quality tolerances below
// ~0.05 dB flag noise.
struct Tolerance {
  double size_growth = 0.005;
  double psnr_drop = 0.05;
};

// One line per regression, naming the scan, voxel size, codec row and target, the two values, the
// baseline's and this report's versions and settings. Cases or rows missing from either side are
// not compared (a corpus may change); a case that failed now but not in the baseline is one.
std::vector<std::string> FindRegressions(const nlohmann::json& report, const nlohmann::json& baseline, const Tolerance& tolerance);

// Reports in `dir` (report-*.json), oldest first; unreadable ones are skipped.
std::vector<std::filesystem::path> ListReports(const std::filesystem::path& dir);
StatusOr<nlohmann::json> ReadReport(const std::filesystem::path& file);

}  // namespace pointdag
