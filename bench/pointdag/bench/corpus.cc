#include "pointdag/bench/corpus.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "pointdag/ingest.h"
#include "pointdag/read/scan_reader.h"

namespace pointdag {
namespace {

StatusOr<double> DerivedVoxel(const std::filesystem::path& scan) {
  ASSIGN_OR_RETURN(std::unique_ptr<ScanReader> reader, OpenScan(scan));
  return DeriveVoxelSize(*reader);
}

Status CheckTargets(const std::vector<double>& targets, const std::string& where) {
  if (targets.empty()) return InvalidArgument(where + ": targets is empty");
  for (double t : targets) {
    if (!(t >= 10 && t <= 99)) return InvalidArgument(where + ": target " + std::to_string(t) + " dB is outside 10..99");
  }
  return Status::Ok();
}

// `key` of `table` as a list of numbers, or nullopt when absent.
StatusOr<std::optional<std::vector<double>>> Targets(const toml::table& table, const std::string& where) {
  const toml::node* node = table.get("targets");
  if (!node) return std::optional<std::vector<double>>{};
  const toml::array* list = node->as_array();
  if (!list) return InvalidArgument(where + ": targets must be a list of numbers (dB)");
  std::vector<double> out;
  for (const toml::node& item : *list) {
    const std::optional<double> v = item.value<double>();
    if (!v) return InvalidArgument(where + ": targets must be a list of numbers (dB)");
    out.push_back(*v);
  }
  RETURN_IF_ERROR(CheckTargets(out, where));
  return std::optional<std::vector<double>>(std::move(out));
}

StatusOr<std::vector<CorpusCase>> LoadFolder(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<CorpusCase> cases;
  for (const auto& file : files) {
    auto voxel = DerivedVoxel(file);
    if (!voxel.ok() && voxel.status().code() == StatusCode::kUnsupported) continue;  // not a scan (README, checksums)
    if (!voxel.ok()) return Status(voxel.status().code(), file.string() + ": " + voxel.status().message());
    cases.push_back({file, *voxel, true, kDefaultCorpusTargets});
  }
  if (cases.empty()) return InvalidArgument(folder.string() + " holds no scan");
  return cases;
}

StatusOr<std::vector<CorpusCase>> LoadToml(const std::filesystem::path& file) {
  toml::table root;
  try {
    root = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    return InvalidArgument(file.string() + ":" + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
  }
  ASSIGN_OR_RETURN(const auto common, Targets(root, file.string()));
  const toml::array* scans = root.get_as<toml::array>("scan");
  if (!scans || scans->empty()) return InvalidArgument(file.string() + ": no [[scan]] entries");
  std::vector<CorpusCase> cases;
  for (size_t i = 0; i < scans->size(); ++i) {
    const std::string where = file.string() + ": scan " + std::to_string(i + 1);
    const toml::table* entry = scans->get(i)->as_table();
    if (!entry) return InvalidArgument(where + " is not a table");
    const std::optional<std::string> name = entry->get("file") ? entry->get("file")->value<std::string>() : std::nullopt;
    if (!name || name->empty()) return InvalidArgument(where + ": file is missing");
    CorpusCase c;
    c.scan = std::filesystem::path(*name).is_absolute() ? std::filesystem::path(*name) : file.parent_path() / *name;
    if (!std::filesystem::is_regular_file(c.scan)) return IoError(where + ": " + c.scan.string() + " does not exist");
    if (const toml::node* voxel = entry->get("voxel")) {
      const std::optional<double> v = voxel->value<double>();
      if (!v || !(*v > 0) || !std::isfinite(*v)) return InvalidArgument(where + ": voxel must be a positive number");
      c.voxel = *v;
    } else {
      auto derived = DerivedVoxel(c.scan);
      if (!derived.ok()) return Status(derived.status().code(), where + ": " + derived.status().message());
      c.voxel = *derived;
      c.voxel_derived = true;
    }
    ASSIGN_OR_RETURN(const auto own, Targets(*entry, where));
    c.targets = own ? *own : common ? *common : kDefaultCorpusTargets;
    cases.push_back(std::move(c));
  }
  return cases;
}

}  // namespace

StatusOr<std::vector<CorpusCase>> LoadCorpus(const std::filesystem::path& corpus) {
  std::error_code ec;
  if (std::filesystem::is_directory(corpus, ec)) return LoadFolder(corpus);
  if (!std::filesystem::is_regular_file(corpus, ec)) return IoError("corpus " + corpus.string() + " does not exist");
  return LoadToml(corpus);
}

}  // namespace pointdag
