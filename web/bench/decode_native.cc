// The native reference of web/bench/decode_bench.mjs: DecodePdag (what `pointdag decode` runs,
// without the process start and the PLY) on tile files, in one process.
//   decode_native_bench REPS TILE.pdag... -> the median milliseconds of a pass over all tiles
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "pointdag/pipeline.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s REPS TILE.pdag...\n", argv[0]);
    return 2;
  }
  const int reps = std::atoi(argv[1]);
  std::vector<std::vector<uint8_t>> tiles;
  for (int i = 2; i < argc; ++i) {
    auto bytes = pointdag::ReadFileBytes(argv[i]);
    if (!bytes.ok()) {
      std::fprintf(stderr, "%s\n", bytes.status().ToString().c_str());
      return 1;
    }
    tiles.push_back(std::move(*bytes));
  }
  std::vector<double> passes;
  for (int rep = -1; rep < reps; ++rep) {  // one warm-up pass
    const auto start = std::chrono::steady_clock::now();
    for (const auto& bytes : tiles) {
      auto file = pointdag::ParsePdag(bytes);  // as `pointdag decode`: parse, then decode
      auto decoded = file.ok() ? pointdag::DecodePdag(*file) : file.status();
      if (!decoded.ok()) {
        std::fprintf(stderr, "%s\n", decoded.status().ToString().c_str());
        return 1;
      }
    }
    if (rep >= 0) passes.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(passes.begin(), passes.end());
  std::printf("%.3f\n", passes[passes.size() / 2]);
  return 0;
}
