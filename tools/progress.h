// A progress bar on stderr for large inputs; silent when stderr is not a terminal.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <string>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

constexpr uint64_t kProgressMinPoints = 1'000'000;

inline ProgressFn MakeProgressBar(const std::string& label) {
  if (!isatty(STDERR_FILENO)) return nullptr;
  return [label, shown = -1](uint64_t done, uint64_t total) mutable {
    if (total < kProgressMinPoints) return;
    const int percent = static_cast<int>(100 * done / total);
    if (percent == shown) return;
    shown = percent;
    const int width = 40, filled = width * percent / 100;
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%%", label.c_str(), filled, "========================================",
                 width - filled, "", percent);
    if (done >= total) std::fputc('\n', stderr);
    std::fflush(stderr);
  };
}

}  // namespace pointdag
