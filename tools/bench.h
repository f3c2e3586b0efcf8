// `pointdag bench`: the codec-core benchmark over a folder of scans (a command, not a test).
#pragma once

#include <string>

namespace pointdag {

struct BenchOptions {
  std::string data_dir = "../shared/data";
  bool json = false;
};

int RunBench(const BenchOptions& options);

}  // namespace pointdag
