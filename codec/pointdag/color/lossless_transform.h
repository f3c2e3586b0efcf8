// Lossless colors version 4 (proto/PDAG_FORMAT.md §3): the stream's layout byte, chosen by the
// encoder: which channel leads version 3's coder (it predicts the second and third as the first
// plus their neighbours' mean difference from it and a learned share of the first's miss), and
// whether the predictions take the columns around each voxel (causal_columns.h). What each gave is
// in docs/benchmarks.md ("Lossless colors, version 4").
#pragma once

#include <cstdint>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag::lossless {

// Channel orders, (lead, second, third) into the coder's (G, R, B): 0 = (G, R, B) (version 3's),
// 1 = (G, B, R), 2 = (R, G, B), 3 = (R, B, G), 4 = (B, G, R), 5 = (B, R, G).
constexpr int kChannelOrders = 6;

struct Layout {
  int order = 0;         // 0..kChannelOrders - 1
  bool columns = false;  // neighbour mode only
  uint8_t Byte() const { return static_cast<uint8_t>(order | (columns ? 8 : 0)); }
};

// False for a byte that names no layout.
bool LayoutOf(uint8_t byte, Layout& layout);

Rgb8 Reorder(Rgb8 c, int order);
Rgb8 Restore(Rgb8 c, int order);

}  // namespace pointdag::lossless
