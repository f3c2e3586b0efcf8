#include "pointdag/bench/report.h"

#include <draco/core/draco_version.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>

#include "pointdag/bench/corpus_case.h"

namespace pointdag {
namespace {

std::string UtcStamp(std::time_t t, const char* format) {
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof(buf), format, &tm);
  return buf;
}

std::string CaseName(const nlohmann::json& c) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), " at voxel %g", JsonNumber(c, "voxel"));
  return c.value("scan", std::string("?")) + buf;
}

std::string Provenance(const nlohmann::json& report) {
  const auto versions = report.find("versions");
  const auto settings = report.find("settings");
  const auto id = report.find("id");
  return "pointdag " + (versions != report.end() ? versions->value("pointdag", std::string("?")) : std::string("?")) +
         ", report " + (id != report.end() && id->is_string() ? id->get<std::string>() : std::string("?")) + ", settings " +
         (settings != report.end() ? settings->dump() : std::string("{}"));
}


const nlohmann::json* FindCase(const nlohmann::json& report, const nlohmann::json& c) {
  for (const auto& other : report["cases"]) {
    if (!other.is_object()) continue;
    if (other.value("scan", "") == c.value("scan", "") && JsonNumber(other, "voxel") == JsonNumber(c, "voxel")) return &other;
  }
  return nullptr;
}

}  // namespace

std::string MachineName() {
  utsname u{};
  uname(&u);
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  return model + ", " + std::to_string(sysconf(_SC_NPROCESSORS_ONLN)) + " cores, " + u.sysname + " " + u.machine;
}

std::string PointdagVersion() { return POINTDAG_GIT_DESCRIBE; }
std::string DracoVersion() { return draco::kDracoVersion; }

nlohmann::json MakeReport(std::vector<nlohmann::json> cases, const std::string& corpus, const nlohmann::json& settings) {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  return {{"schema", 1},
          {"id", UtcStamp(now, "%Y%m%dT%H%M%SZ")},
          {"created", UtcStamp(now, "%Y-%m-%dT%H:%M:%SZ")},
          {"machine", {{"cpu", MachineName()}, {"cores", sysconf(_SC_NPROCESSORS_ONLN)}}},
          {"versions", {{"pointdag", PointdagVersion()}, {"draco", DracoVersion()}}},
          {"corpus", corpus},
          {"settings", settings},
          {"cases", std::move(cases)}};
}

std::vector<std::string> FindRegressions(const nlohmann::json& report, const nlohmann::json& baseline, const Tolerance& tolerance) {
  std::vector<std::string> out;
  const std::string since = " (baseline: " + Provenance(baseline) + "; now: " + Provenance(report) + ")";
  const auto larger = [&](double now, double then) { return now > then * (1 + tolerance.size_growth); };
  char buf[256];
  for (const auto& c : report["cases"]) {
    const nlohmann::json* old = FindCase(baseline, c);
    if (!old) continue;
    if (c.contains("error")) {
      if (!old->contains("error")) out.push_back(CaseName(c) + ": failed: " + c["error"].dump() + since);
      continue;
    }
    if (old->contains("error")) continue;
    const double geometry = JsonNumber(c, "geometry_bits_per_voxel"), old_geometry = JsonNumber(*old, "geometry_bits_per_voxel");
    if (larger(geometry, old_geometry)) {
      std::snprintf(buf, sizeof(buf), ": geometry grew from %.4f to %.4f bits/voxel (+%.2f%%)", old_geometry, geometry,
                    100 * (geometry / old_geometry - 1));
      out.push_back(CaseName(c) + buf + since);
    }
    std::map<std::string, const nlohmann::json*> old_rows;
    const nlohmann::json old_ours = old->value("ours", nlohmann::json::array());
    for (const auto& row : old_ours) old_rows[CodecRowKey(row)] = &row;
    for (const auto& row : c.value("ours", nlohmann::json::array())) {
      const std::string key = CodecRowKey(row);
      const auto it = old_rows.find(key);
      if (it == old_rows.end()) continue;
      const nlohmann::json& then = *it->second;
      const double bits = JsonNumber(row, "bits_per_point"), old_bits = JsonNumber(then, "bits_per_point");
      if (larger(bits, old_bits)) {
        std::snprintf(buf, sizeof(buf), ": %s grew from %.4f to %.4f bits/point (+%.2f%%)", key.c_str(), old_bits, bits,
                      100 * (bits / old_bits - 1));
        out.push_back(CaseName(c) + buf + since);
      }
      const double psnr = JsonNumber(row, "psnr_y"), old_psnr = JsonNumber(then, "psnr_y");
      if (psnr < old_psnr - tolerance.psnr_drop) {
        std::snprintf(buf, sizeof(buf), ": %s PSNR-Y fell from %.3f to %.3f dB", key.c_str(), old_psnr, psnr);
        out.push_back(CaseName(c) + buf + since);
      }
    }
  }
  return out;
}

std::vector<std::filesystem::path> ListReports(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && name.rfind("report-", 0) == 0 && entry.path().extension() == ".json") out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());  // ids are UTC times: names sort by age
  return out;
}

StatusOr<nlohmann::json> ReadReport(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return IoError("cannot read report " + file.string());
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json report = nlohmann::json::parse(text.str(), nullptr, false);
  const auto is_report = [&] {
    if (report.is_discarded() || !report.is_object() || !report.contains("cases") || !report["cases"].is_array()) return false;
    for (const auto& c : report["cases"]) {
      if (!c.is_object() || !c.value("scan", nlohmann::json()).is_string()) return false;
      const auto ours = c.find("ours");
      if (ours == c.end()) continue;
      if (!ours->is_array()) return false;
      for (const auto& row : *ours) {
        if (!row.is_object() || !row.value("codec", nlohmann::json()).is_string()) return false;
      }
    }
    return true;
  };
  if (!is_report()) return Malformed(file.string() + " is not a pointdag benchmark report");
  return report;
}

}  // namespace pointdag
