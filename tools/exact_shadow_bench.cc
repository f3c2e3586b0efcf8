// `pointdag bench --shadow`, second table: the exact per-voxel shadows (voxel_shadows.h) on one and two
// threads, and sun hours of a day's 24 suns, on the scans of docs/benchmarks.md at their voxel sizes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bench.h"
#include "pointdag/dag/dag_builder.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/voxelize/voxelizer.h"
#include "shadow_bench.h"

namespace pointdag {
namespace {

struct ScanAtVoxel {
  const char* file;
  double voxel;
};
constexpr ScanAtVoxel kScans[] = {
    {"lion_takanawa_pdrf7_rgb.las", 0.01},   {"lion_takanawa_pdrf7_rgb.las", 0.005},
    {"pcx_guanyin_cc-by-4.0_rgb.ply", 0.002}, {"pcx_guanyin_cc-by-4.0_rgb.ply", 0.001},
    {"autzen_trim_pdrf3_rgb.las", 4.0},       {"autzen_trim_pdrf3_rgb.las", 2.0},
};

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Light Travelling(double x, double y, double z) {
  const double n = std::sqrt(x * x + y * y + z * z);
  return Light{{x / n, y / n, z / n}, false};
}

// 24 suns over a day's arc: elevation 10..80..10 degrees while the azimuth goes 90..270.
std::vector<Light> DayArc() {
  std::vector<Light> day;
  const double pi = std::acos(-1.0);
  for (int i = 0; i < 24; ++i) {
    const double f = (i + 0.5) / 24, azimuth = pi / 2 + f * pi, elevation = (10 + 70 * std::sin(f * pi)) * pi / 180;
    day.push_back(Travelling(-std::sin(azimuth) * std::cos(elevation), -std::cos(azimuth) * std::cos(elevation),
                             -std::sin(elevation)));
  }
  return day;
}

}  // namespace

int RunExactShadowBench(const std::filesystem::path& data_dir, std::ostream& out) {
  // The sun 35 degrees high in the south-east (azimuth 135): it travels north-west and down.
  const Light sun = Travelling(-0.579, 0.579, -0.574);
  const std::vector<Light> day = DayArc();
  out << "\nexact voxel shadows (ShadowedVoxels), light travelling (-0.579, 0.579, -0.574), best of 3; sun hours: "
         "24 suns of a day's arc, 2 threads, one run\n\n"
      << "| scan | voxel | depth | voxels | shadowed | 1 thread s | voxels/s | 2 threads s | voxels/s | 24 suns s |\n"
      << "|---|---|---|---|---|---|---|---|---|---|\n";
  int failures = 0;
  std::string absent;
  for (const auto& scan : kScans) {
    if (!std::filesystem::exists(data_dir / scan.file)) {
      if (absent.find(scan.file) == std::string::npos) absent += std::string(" ") + scan.file;
      continue;
    }
    auto reader = OpenScan(data_dir / scan.file);
    VoxelizeOptions options;
    options.voxel_size = scan.voxel;
    auto grid = reader.ok() ? Voxelize(**reader, options) : StatusOr<VoxelGrid>(reader.status());
    auto dag = grid.ok() ? BuildDag(grid->morton, grid->depth) : StatusOr<Svdag>(grid.status());
    if (!dag.ok()) {
      out << "| " << scan.file << " | " << scan.voxel << " | error: " << dag.status().ToString() << " |\n";
      ++failures;
      continue;
    }
    double best[2] = {1e9, 1e9};
    size_t shadowed = 0;
    for (int threads : {1, 2}) {
      for (int run = 0; run < 3; ++run) {
        const auto start = std::chrono::steady_clock::now();
        auto result = ShadowedVoxels(*dag, sun, threads);
        best[threads - 1] = std::min(best[threads - 1], Since(start));
        if (!result.ok()) return 1;
        shadowed = static_cast<size_t>(std::count(result->begin(), result->end(), 1));
      }
    }
    const auto start = std::chrono::steady_clock::now();
    if (!LitSampleCounts(*dag, day, 2).ok()) return 1;
    const double hours = Since(start);
    const double n = static_cast<double>(grid->morton.size());
    char row[512];
    std::snprintf(row, sizeof(row), "| %s | %g | %d | %zu | %zu | %.3f | %.2f M | %.3f | %.2f M | %.2f |\n", scan.file,
                  scan.voxel, grid->depth, grid->morton.size(), shadowed, best[0], n / best[0] / 1e6, best[1],
                  n / best[1] / 1e6, hours);
    out << row << std::flush;
  }
  if (!absent.empty()) out << "\nnot in " << data_dir.string() << ":" << absent << "\n";
  return failures == 0 ? 0 : 1;
}

}  // namespace pointdag
