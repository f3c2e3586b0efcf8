// `pointdag bench --corpus CORPUS --out DIR`: the nightly compression benchmark (issue #15).
// Runs every case of the corpus in its own child process (so that peak RSS is the case's), writes
// DIR/report-ID.json and DIR/report-ID.html, prints a table, and compares with a baseline (the
// newest earlier report in DIR, or --baseline): exit 0, 1 on an error, 3 on a regression.
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "bench.h"
#include "pointdag/bench/corpus.h"
#include "pointdag/bench/corpus_case.h"
#include "pointdag/bench/report.h"
#include "pointdag/bench/report_html.h"
#include "pointdag/container/pdag_file.h"

namespace pointdag {
namespace {

constexpr int kExitRegression = 3;
constexpr size_t kTrendReports = 30;  // how many earlier reports the HTML trend shows

Status WriteText(const std::filesystem::path& path, const std::string& text) {
  return WriteFileAtomically(path, std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

void PrintTable(const nlohmann::json& report) {
  std::printf("machine: %s; pointdag %s, libdraco %s\n\n", report["machine"]["cpu"].get<std::string>().c_str(),
              report["versions"]["pointdag"].get<std::string>().c_str(), report["versions"]["draco"].get<std::string>().c_str());
  std::printf("| scan | voxel | voxels | geometry b/vox | codec | target dB | PSNR-Y dB | b/pt | Draco b/pt | ours/Draco |\n"
              "|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& c : report["cases"]) {
    if (c.contains("error")) {
      std::printf("| %s | %g | error: %s |\n", c["scan"].get<std::string>().c_str(), JsonNumber(c, "voxel"),
                  c["error"].get<std::string>().c_str());
      continue;
    }
    const double draco = JsonNumber(c, "draco_bits_per_point");
    for (const auto& row : c["ours"]) {
      const std::string codec = row.contains("image_codec") ? "image (" + row["image_codec"].get<std::string>() + "/" +
                                                                  row["curve"].get<std::string>() + ")"
                                                            : row["codec"].get<std::string>();
      std::printf("| %s | %g | %zu | %.3f | %s | %s | %s | %.3f | %.3f | %.3f |\n", c["scan"].get<std::string>().c_str(),
                  JsonNumber(c, "voxel"), c["voxels"].get<size_t>(), JsonNumber(c, "geometry_bits_per_voxel"), codec.c_str(),
                  row["target_psnr"].is_number() ? std::to_string(row["target_psnr"].get<int>()).c_str() : "-",
                  row["psnr_y"].is_number() ? std::to_string(row["psnr_y"].get<double>()).substr(0, 5).c_str() : "lossless",
                  JsonNumber(row, "bits_per_point"), draco, JsonNumber(row, "bits_per_point") / draco);
    }
  }
  std::printf("\n| scan | voxel | encode Mvox/s ours | Draco -cl 10 | decode Mvox/s ours | Draco | peak RSS MiB |\n"
              "|---|---|---|---|---|---|---|\n");
  for (const auto& c : report["cases"]) {
    if (c.contains("error")) continue;
    const auto& s = c["speed"];
    std::printf("| %s | %g | %.2f | %.2f | %.2f | %.2f | %.0f |\n", c["scan"].get<std::string>().c_str(), JsonNumber(c, "voxel"),
                JsonNumber(s, "ours_encode_points_per_second") / 1e6, JsonNumber(s, "draco_encode_points_per_second") / 1e6,
                JsonNumber(s, "ours_decode_points_per_second") / 1e6, JsonNumber(s, "draco_decode_points_per_second") / 1e6,
                JsonNumber(c, "peak_rss_bytes") / 1048576.0);
  }
}

}  // namespace

int RunCorpusBench(const BenchOptions& options) {
  const auto fail = [](const Status& s) {
    std::cerr << "pointdag bench --corpus: " << s.ToString() << "\n";
    return 1;
  };
  auto cases = LoadCorpus(options.corpus);
  if (!cases.ok()) return fail(cases.status());
  const std::filesystem::path dir = options.out_dir;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return fail(IoError("cannot create " + dir.string() + ": " + ec.message()));

  std::vector<nlohmann::json> history;
  for (const auto& file : ListReports(dir)) {
    if (auto r = ReadReport(file); r.ok()) history.push_back(std::move(*r));
  }
  std::optional<nlohmann::json> baseline;
  if (!options.baseline.empty()) {
    auto r = ReadReport(options.baseline);
    if (!r.ok()) return fail(r.status());
    baseline = std::move(*r);
  } else if (!history.empty()) {
    baseline = history.back();
  }

  const bool terminal = isatty(STDERR_FILENO);
  std::vector<nlohmann::json> results;
  for (size_t i = 0; i < cases->size(); ++i) {
    const CorpusCase& c = (*cases)[i];
    if (terminal) std::fprintf(stderr, "\r[%zu/%zu] %s at voxel %g ...\033[K", i + 1, cases->size(), c.scan.filename().c_str(), c.voxel);
    results.push_back(RunIsolated(c.scan.filename().string(), [&] { return RunCorpusCase(c); }));
  }
  if (terminal) std::fprintf(stderr, "\r\033[K");

  const char* device = std::getenv("POINTDAG_DEVICE");
  const nlohmann::json settings = {{"draco", "every method and speed, smallest kept; -cl 10 kd-tree timed"},
                                   {"speed_target_psnr", 38.0},
                                   {"geometry_coder", "spatial"},
                                   {"device", device ? device : "auto"},
                                   {"size_tolerance", options.size_tolerance},
                                   {"psnr_tolerance_db", options.psnr_tolerance}};
  const nlohmann::json report = MakeReport(std::move(results), options.corpus, settings);
  const std::string id = report["id"];
  if (history.size() > kTrendReports) history.erase(history.begin(), history.end() - kTrendReports);
  if (Status s = WriteText(dir / ("report-" + id + ".json"), report.dump(1) + "\n"); !s.ok()) return fail(s);
  if (Status s = WriteText(dir / ("report-" + id + ".html"), ReportHtml(report, history)); !s.ok()) return fail(s);
  if (options.keep_reports > 0) {
    const auto reports = ListReports(dir);
    for (size_t i = 0; i + options.keep_reports < reports.size(); ++i) {
      std::filesystem::remove(reports[i], ec);
      std::filesystem::remove(std::filesystem::path(reports[i]).replace_extension(".html"), ec);
    }
  }
  PrintTable(report);
  std::printf("\nreport: %s\n", (dir / ("report-" + id + ".html")).c_str());

  bool failed_case = false;
  for (const auto& c : report["cases"]) failed_case |= c.contains("error");
  if (!baseline) return failed_case ? 1 : 0;
  const auto regressions = FindRegressions(report, *baseline, {options.size_tolerance, options.psnr_tolerance});
  for (const auto& line : regressions) std::cerr << "regression: " << line << "\n";
  if (!regressions.empty()) return kExitRegression;
  return failed_case ? 1 : 0;
}

}  // namespace pointdag
