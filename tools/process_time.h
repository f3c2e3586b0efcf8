// Whole-process timing for the benchmarks: a command run as a child pinned to one core, its CPU
// seconds (user + system, from wait4's rusage) rather than wall time, so that another process on the
// machine's other core disturbs the figure as little as possible.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "pointdag/status.h"

namespace pointdag {

struct ProcessRun {
  std::vector<std::string> argv;                            // argv[0]: a path, or a name looked up in PATH
  std::vector<std::pair<std::string, std::string>> env;     // set in the child on top of ours
  int core = 0;                                             // the CPU the child is pinned to
};

// The child's user + system CPU seconds; kIoError when it cannot start or exits non-zero (its
// stderr is the caller's, so its message shows).
StatusOr<double> ProcessCpuSeconds(const ProcessRun& run);

// The smallest of `runs` runs (the least disturbed one).
StatusOr<double> BestProcessCpuSeconds(const ProcessRun& run, int runs);

// The executable's path when `name` is found in PATH (or is a path to an executable), else empty.
std::string FindExecutable(const std::string& name);

}  // namespace pointdag
