#include "shadow_bench.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "bench.h"
#include "pointdag/bench/report.h"
#include "pointdag/dag/dag_builder.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/shadow/shadow_dag.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/voxelize/morton.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {
namespace {

// Grid depths measured: 8 and 10, or the comma list in POINTDAG_SHADOW_DEPTHS (each 2..19).
std::vector<int> Depths() {
  std::vector<int> depths;
  if (const char* env = std::getenv("POINTDAG_SHADOW_DEPTHS")) {
    for (const char* p = env; *p != '\0';) {
      char* end = nullptr;
      const long d = std::strtol(p, &end, 10);
      if (end == p || d < 2 || d > 19) return {};
      depths.push_back(static_cast<int>(d));
      p = *end == ',' ? end + 1 : end;
    }
    return depths;
  }
  return {8, 10};
}
constexpr int kQueries = 1 << 21;
// The free-space mode visits the shadow volumes' walls cell by cell: seconds at depth 10, much more beyond.
constexpr int kFreeSpaceMaxDepth = 10;
// A sun 45 degrees high in the south-west, travelling north-east and down.
const Light kSun{{0.5, 0.5, -std::sqrt(0.5)}, false};

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

nlohmann::json ShadowCase(const std::filesystem::path& scan, int depth) {
  auto reader = OpenScan(scan);
  if (!reader.ok()) return {{"error", reader.status().ToString()}};
  VoxelizeOptions voxelize;
  voxelize.depth = depth;
  auto grid = Voxelize(**reader, voxelize);
  if (!grid.ok()) return {{"error", grid.status().ToString()}};
  auto dag = BuildDag(grid->morton, grid->depth);
  if (!dag.ok()) return {{"error", dag.status().ToString()}};
  const std::vector<uint64_t> codes = std::move(grid->morton);
  grid = VoxelGrid{};

  // The exact answers alone (voxel_shadows.h), then the whole build, which includes them; best of 3.
  double exact_s = 1e30, build_s = 1e30;
  std::vector<uint8_t> exact;
  for (int run = 0; run < 3; ++run) {
    const auto start = std::chrono::steady_clock::now();
    auto answers = ShadowedVoxels(*dag, kSun);
    if (!answers.ok()) return {{"error", answers.status().ToString()}};
    exact_s = std::min(exact_s, Since(start));
    exact = std::move(*answers);
  }
  malloc_trim(0);
  std::ofstream("/proc/self/clear_refs") << "5";
  const uint64_t baseline = RssAndPeak().first;
  auto shadow = BuildShadowDag(*dag, kSun);
  if (!shadow.ok()) return {{"error", shadow.status().ToString()}};
  const uint64_t peak = RssAndPeak().second;
  build_s = shadow->stats().build_seconds;
  for (int run = 0; run < 2; ++run) {
    auto again = BuildShadowDag(*dag, kSun);
    if (again.ok()) build_s = std::min(build_s, again->stats().build_seconds);
  }
  // What each relaxation step gains: none (undefined = lit), collapse with mixed subtrees' undefined
  // cells lit, collapse with matching (the default, collapse with the majority rule, is `shadow`).
  ShadowBuildOptions options;
  options.relax_undefined = false;
  auto unrelaxed = BuildShadowDag(*dag, kSun, options);
  options.relax_undefined = true;
  options.fill = UndefinedFill::kLit;
  auto collapsed = BuildShadowDag(*dag, kSun, options);
  options.fill = UndefinedFill::kMatch;
  auto matched = BuildShadowDag(*dag, kSun, options);
  if (!unrelaxed.ok() || !collapsed.ok() || !matched.ok()) return {{"error", "a relaxation variant failed"}};
  // Free space defined too (answers in the air), up to kFreeSpaceMaxDepth; its own peak RSS.
  double free_bytes = -1, free_s = -1, free_rss = -1;
  if (depth <= kFreeSpaceMaxDepth) {
    options = ShadowBuildOptions{};
    options.define_free_space = true;
    malloc_trim(0);
    std::ofstream("/proc/self/clear_refs") << "5";
    const uint64_t free_baseline = RssAndPeak().first;
    auto free_space = BuildShadowDag(*dag, kSun, options);
    if (!free_space.ok()) return {{"error", free_space.status().ToString()}};
    free_rss = static_cast<double>(RssAndPeak().second - free_baseline);
    free_bytes = static_cast<double>(free_space->stats().shadow_dag_bytes);
    free_s = free_space->stats().build_seconds;
  }

  // Random surface voxels: their centres, one query each; every answer checked against `exact`.
  std::mt19937_64 rng(16);
  std::vector<uint32_t> picks(kQueries);
  for (auto& p : picks) p = static_cast<uint32_t>(rng() % codes.size());
  std::vector<std::array<double, 3>> points(kQueries);
  for (size_t i = 0; i < points.size(); ++i) {
    const auto [x, y, z] = MortonDecode(codes[picks[i]]);
    points[i] = {x + 0.5, y + 0.5, z + 0.5};
  }
  double query_s = 1e30;
  uint64_t wrong = 0;
  for (int run = 0; run < 3; ++run) {
    wrong = 0;
    const auto start = std::chrono::steady_clock::now();
    for (size_t i = 0; i < points.size(); ++i) wrong += shadow->Shadowed(points[i]) != (exact[picks[i]] != 0);
    query_s = std::min(query_s, Since(start));
  }
  const ShadowDagStats& s = shadow->stats();
  return {{"scan", scan.filename().string()},
          {"depth", depth},
          {"voxels", s.surface_voxels},
          {"shadowed", s.shadowed_voxels},
          {"light_depth", s.light_depth},
          {"dag_bytes", s.shadow_dag_bytes},
          {"collapse_only_bytes", collapsed->stats().shadow_dag_bytes},
          {"match_bytes", matched->stats().shadow_dag_bytes},
          {"free_space_bytes", free_bytes},
          {"free_space_s", free_s},
          {"free_space_rss_bytes", free_rss},
          {"unrelaxed_bytes", unrelaxed->stats().shadow_dag_bytes},
          {"dense_bytes", s.dense_grid_bytes},
          {"map_bytes", s.shadow_map_bytes},
          {"exact_s", exact_s},
          {"build_s", build_s},
          {"own_peak_bytes", s.build_peak_bytes},
          {"rss_peak_over_baseline_bytes", peak - baseline},
          {"queries_per_s", kQueries / query_s},
          {"wrong_answers", wrong}};
}

// "n/a" where the DAG is a bare all-lit or all-shadowed root (0 bytes).
std::string Ratio(double whole, double dag) {
  if (dag == 0) return "n/a";
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", whole / dag);
  return text;
}

std::string Seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", s);
  return text;
}

// "–" for a figure not measured (negative).
std::string Skipped(double value, const std::string& text) { return value < 0 ? "–" : text; }

std::string Bytes(double b) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (b >= 1024 && u < 6) b /= 1024, ++u;
  char text[32];
  std::snprintf(text, sizeof(text), u == 0 ? "%.0f %s" : "%.1f %s", b, units[u]);
  return text;
}

}  // namespace

int RunShadowBench(const std::filesystem::path& data_dir, std::ostream& out) {
  std::vector<std::filesystem::path> scans;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(data_dir, ec)) {
    const auto ext = entry.path().extension();
    if (entry.is_regular_file() && (ext == ".las" || ext == ".ply" || ext == ".pcd")) scans.push_back(entry.path());
  }
  if (ec || scans.empty()) {
    out << "no scans in " << data_dir << "\n";
    return 1;
  }
  const std::vector<int> depths = Depths();
  if (depths.empty()) {
    out << "POINTDAG_SHADOW_DEPTHS must be a comma list of depths 2..19\n";
    return 1;
  }
  std::sort(scans.begin(), scans.end());
  out << "machine: " << MachineName() << "; light travelling (0.5, 0.5, -0.707) (sun 45 degrees high), "
      << "light_depth = depth + 2; build and exact times best of 3; queries: " << kQueries
      << " random voxel centres, one core, best of 3\n\n"
      << "| scan | depth | voxels | shadowed | light depth | DAG | no relax | collapse, lit | collapse, match | "
         "dense grid | shadow map | dense / DAG | map / DAG | DAG bits/voxel | exact s | build s | peak RSS | "
         "own peak | Mq/s | wrong | free space | free s | free RSS |\n"
      << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  int failures = 0;
  for (const auto& scan : scans) {
    for (int depth : depths) {
      const nlohmann::json r = RunIsolated(scan.filename().string(), [&] { return ShadowCase(scan, depth); });
      if (r.contains("error")) {
        out << "| " << scan.filename().string() << " | " << depth << " | error: " << r["error"].dump() << " |\n";
        ++failures;
        continue;
      }
      const auto n = [&](const char* key) { return r[key].get<double>(); };
      char row[768];
      std::snprintf(row, sizeof(row),
                    "| %s | %d | %.0f | %.0f | %d | %s | %s | %s | %s | %s | %s | %s | %s | %.2f | %.3f | %.3f | %s | "
                    "%s | %.2f | %.0f | %s | %s | %s |\n",
                    scan.filename().c_str(), depth, n("voxels"), n("shadowed"), r["light_depth"].get<int>(),
                    Bytes(n("dag_bytes")).c_str(), Bytes(n("unrelaxed_bytes")).c_str(),
                    Bytes(n("collapse_only_bytes")).c_str(), Bytes(n("match_bytes")).c_str(), Bytes(n("dense_bytes")).c_str(),
                    Bytes(n("map_bytes")).c_str(), Ratio(n("dense_bytes"), n("dag_bytes")).c_str(),
                    Ratio(n("map_bytes"), n("dag_bytes")).c_str(),
                    8 * n("dag_bytes") / n("voxels"), n("exact_s"), n("build_s"),
                    Bytes(n("rss_peak_over_baseline_bytes")).c_str(), Bytes(n("own_peak_bytes")).c_str(),
                    n("queries_per_s") / 1e6, n("wrong_answers"), Skipped(n("free_space_bytes"), Bytes(n("free_space_bytes"))).c_str(),
                    Skipped(n("free_space_s"), Seconds(n("free_space_s"))).c_str(),
                    Skipped(n("free_space_rss_bytes"), Bytes(n("free_space_rss_bytes"))).c_str());
      out << row << std::flush;
      failures += r["wrong_answers"].get<uint64_t>() != 0;
    }
  }
  return RunExactShadowBench(data_dir, out) == 0 && failures == 0 ? 0 : 1;
}

}  // namespace pointdag
