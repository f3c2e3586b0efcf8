// `pointdag bench`: the codec-core benchmark over a folder of scans (a command, not a test).
#pragma once

#include <cstdint>
#include <string>

namespace pointdag {

struct BenchOptions {
  std::string data_dir = "../shared/data";
  bool json = false;
  bool colors = false;  // the color codecs' rate-distortion table and decoding speed instead
  bool ingest = false;  // the daemon's pipeline per scan: stage times, points/s, peak RSS
  bool devices = false;  // each stage with Vulkan kernels, CPU path vs Vulkan path
  uint64_t max_points_in_memory = uint64_t{1} << 25;
};

int RunBench(const BenchOptions& options);

}  // namespace pointdag
