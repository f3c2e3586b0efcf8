// The hierarchical colors (colors section codec 8, proto/PDAG_FORMAT.md §3): a lossy coder for low
// rates, one color per voxel (leaf mode). Over the octree of the voxels' Morton codes, every node's
// children's mean colors (YCbCr BT.709, voxel counts as weights) are coded as RAHT's butterflies
// (Haar with weights) of their differences from a prediction: the parent's decoded mean and its
// decoded neighbours' at the parent's and the children's level, as G-PCC's RAHT predicts. The
// differences are quantized with a dead zone (and zeroed where that saves more bits than it costs
// error), chroma's predicted from luma's by a running least-squares fit, and range coded with
// flags mixed from context models (hierarchical_models.h) of the neighbourhood's spread, the
// parent's and the neighbours' coded values.
//
// Not random access: a color depends on its neighbourhood's decoded colors, so the section decodes
// whole (DecodeColors), as the lossless colors do. At 34 dB it takes 11–44 % fewer bits than VBR on
// the benchmark scans, 5–24 % at 38 dB (docs/benchmarks.md); VBR keeps the random-access contract.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/color/color_metrics.h"
#include "pointdag/status.h"

namespace pointdag {

constexpr uint8_t kHierarchicalVersion = 1;

struct HierarchicalSteps {
  uint16_t luma = 16;    // quantizer step of the voxel-level coefficients, in 1/16 of an 8-bit level
  uint16_t chroma = 24;  // the same for Cb and Cr
};

struct HierarchicalColors {
  std::vector<uint8_t> payload;  // after the codec byte
  std::vector<Rgb8> decoded;     // what DecodeHierarchicalColors returns for it
  HierarchicalSteps steps;
  int encodes = 1;  // whole encodes it took (a target's search: 2-5)
};

// `colors`: one per voxel of `morton` (strictly ascending), in that order.
StatusOr<HierarchicalColors> EncodeHierarchicalColors(std::span<const Rgb8> colors, std::span<const uint64_t> morton,
                                                      HierarchicalSteps steps);

// The largest steps whose decoded colors reach `target_psnr_y` (chroma step 1.5 × luma's up to 36
// dB, rising to 2 × at 42 dB), found by a secant search on log(step): a handful of encodes.
// `start`: a luma step (1/16) expected near the answer, 0 to predict one. kInvalidArgument when even the finest step misses the target.
StatusOr<HierarchicalColors> EncodeHierarchicalColorsForTarget(std::span<const Rgb8> colors,
                                                               std::span<const uint64_t> morton, double target_psnr_y,
                                                               uint32_t start = 0);

// `count` and `morton` from decoded geometry. kCorrupt on a payload that is not what the encoder
// writes for that many voxels (wrong count, truncated, trailing bytes).
StatusOr<std::vector<Rgb8>> DecodeHierarchicalColors(std::span<const uint8_t> payload, uint64_t count,
                                                     std::span<const uint64_t> morton);

}  // namespace pointdag
