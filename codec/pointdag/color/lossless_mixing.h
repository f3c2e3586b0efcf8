// Lossless colors version 3 (proto/PDAG_FORMAT.md §3): version 2's prediction from the decoded
// neighbours, reaching to ±4 voxels for a voxel with fewer than 4 within ±2, and each residual's
// binary decisions coded with a logistic mix of four context models instead of one gamma code per
// context. What each part gained is in docs/benchmarks.md ("Lossless colors, version 3").
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag::lossless {

// The range-coded colors (the payload after its header). `morton`: empty (each color predicted
// from the previous one) or one code per color, sorted and unique. `columns` (version 4's column
// mode, with `morton` only): the predictions take the columns around each voxel too.
std::vector<uint8_t> EncodeMixed(std::span<const Rgb8> colors, std::span<const uint64_t> morton, bool columns = false);

// Decodes colors.size() colors into `colors`; false when `coded` does not end where they do.
bool DecodeMixed(std::span<const uint8_t> coded, std::span<Rgb8> colors, std::span<const uint64_t> morton,
                 bool columns = false);

}  // namespace pointdag::lossless
