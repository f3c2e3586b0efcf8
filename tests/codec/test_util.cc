#include "test_util.h"

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "pointdag/pipeline.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag::testing {

StatusOr<EncodedScan> EncodeAutzenAt4Feet() {
  EncodeOptions options;
  options.voxel_size = 4.0;
  return EncodeScan(DataDir() / "autzen_trim_pdrf3_rgb.las", options);
}

CliRun Cli(const std::string& args, const ScratchDir& dir, const std::string& env) {
  const auto err_path = dir / "stderr.txt";
  const std::string command = (env.empty() ? "" : "env " + env + " ") + POINTDAG_CLI + " " + args + " 2>" + err_path.string();
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  char buf[4096];
  for (size_t n; (n = fread(buf, 1, sizeof(buf), pipe)) > 0;) out.append(buf, n);
  const int status = pclose(pipe);
  const auto err = ReadBytes(err_path);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out, std::string(err.begin(), err.end())};
}

std::vector<uint64_t> SurfaceVoxels(int depth, size_t approx, uint32_t seed) {
  std::mt19937 rng(seed);
  const double side = std::ldexp(1.0, depth);
  const uint32_t max_cell = static_cast<uint32_t>(side) - 1;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto cell = [&](double v) { return static_cast<uint32_t>(std::clamp(v, 0.0, static_cast<double>(max_cell))); };
  std::vector<uint64_t> codes;
  for (size_t i = 0; i < approx; ++i) {
    const double u = unit(rng), v = unit(rng);
    switch (i % 3) {
      case 0: {  // a sphere: mostly unique subtrees
        const double theta = 2 * M_PI * u, phi = std::acos(2 * v - 1), r = 0.4 * side;
        codes.push_back(MortonEncode(cell(side / 2 + r * std::sin(phi) * std::cos(theta)),
                                     cell(side / 2 + r * std::sin(phi) * std::sin(theta)),
                                     cell(side / 2 + r * std::cos(phi))));
        break;
      }
      case 1:  // an axis-aligned floor: many identical subtrees
        codes.push_back(MortonEncode(cell(u * side), cell(v * side), cell(side / 8)));
        break;
      default:  // scattered noise
        codes.push_back(MortonEncode(cell(u * side), cell(v * side), cell(unit(rng) * side)));
    }
  }
  std::sort(codes.begin(), codes.end());
  codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
  return codes;
}

}  // namespace pointdag::testing
