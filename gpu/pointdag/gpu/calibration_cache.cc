#include "pointdag/gpu/calibration_cache.h"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <system_error>
#include <vector>

namespace pointdag::gpu {
namespace {

struct Line {
  std::string key, stage;
  StageTiming timing;
};

std::optional<Line> ParseLine(const std::string& text) {
  std::vector<std::string> fields;
  std::istringstream in(text);
  for (std::string field; std::getline(in, field, '\t');) fields.push_back(field);
  if (fields.size() != 4) return std::nullopt;
  Line line{fields[0], fields[1], {}};
  char* end = nullptr;
  line.timing.cpu_seconds = std::strtod(fields[2].c_str(), &end);
  if (*end != '\0' || fields[2].empty()) return std::nullopt;
  line.timing.vulkan_seconds = std::strtod(fields[3].c_str(), &end);
  if (*end != '\0' || fields[3].empty()) return std::nullopt;
  const auto valid = [](double s) { return std::isfinite(s) && s > 0 && s < 3600; };
  if (!valid(line.timing.cpu_seconds) || !valid(line.timing.vulkan_seconds)) return std::nullopt;
  return line;
}

std::vector<Line> ReadLines(const std::filesystem::path& file) {
  std::vector<Line> lines;
  std::ifstream in(file);
  for (std::string text; std::getline(in, text);) {
    if (auto line = ParseLine(text)) lines.push_back(*line);
  }
  return lines;
}

}  // namespace

std::filesystem::path CalibrationCachePath() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg && *xdg) return std::filesystem::path(xdg) / "pointdag" / "calibration.tsv";
  const char* home = std::getenv("HOME");
  if (home && *home) return std::filesystem::path(home) / ".cache" / "pointdag" / "calibration.tsv";
  return {};
}

std::string CalibrationKey(const std::string& device_key) {
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  std::string build = "unknown build";
  if (!error) {
    const auto size = std::filesystem::file_size(exe, error);
    const auto time = std::filesystem::last_write_time(exe, error);
    if (!error) build = std::to_string(size) + "@" + std::to_string(time.time_since_epoch().count());
  }
  std::string key = device_key + " / pointdag " + build;
  for (char& c : key) {
    if (c == '\t' || c == '\n') c = ' ';
  }
  return key;
}

std::optional<StageTiming> LoadCalibration(const std::filesystem::path& file, const std::string& key, Stage stage) {
  if (file.empty()) return std::nullopt;
  for (const Line& line : ReadLines(file)) {
    if (line.key == key && line.stage == StageName(stage)) return line.timing;
  }
  return std::nullopt;
}

void StoreCalibration(const std::filesystem::path& file, const std::string& key, Stage stage, const StageTiming& timing) {
  if (file.empty()) return;
  std::error_code error;
  std::filesystem::create_directories(file.parent_path(), error);
  std::ostringstream out;
  out.precision(17);
  for (const Line& line : ReadLines(file)) {
    if (line.key == key && line.stage != StageName(stage)) {
      out << line.key << '\t' << line.stage << '\t' << line.timing.cpu_seconds << '\t' << line.timing.vulkan_seconds << '\n';
    }
  }
  out << key << '\t' << StageName(stage) << '\t' << timing.cpu_seconds << '\t' << timing.vulkan_seconds << '\n';
  const std::filesystem::path temporary = file.string() + "." + std::to_string(getpid()) + ".tmp";
  {
    std::ofstream write(temporary, std::ios::trunc);
    write << out.str();
    if (!write.good()) {
      std::filesystem::remove(temporary, error);
      return;
    }
  }
  std::filesystem::rename(temporary, file, error);
  if (error) std::filesystem::remove(temporary, error);
}

}  // namespace pointdag::gpu
