// Stage 5d: the block codecs' blocks for a PSNR-Y target, with about one full encode.
//
// The MSE threshold that meets a target is predicted on a sample (16 runs of 2048 colors spread over
// the array, each encoded on its own: a secant search on log(threshold), ~1/8 of an encode per step
// on lion), the whole array is encoded once at the prediction, and the result is corrected
// locally. Any run of whole blocks inside a macro block can be encoded again on its own, so the
// encode is cut into ~32 units at block boundaries, and only the units whose error must change
// are encoded again at a scaled threshold (largest error first); a raised unit is kept only where
// the total still meets the target, and raising (for bytes only) stops after three rounds or at a
// round that left the error no larger. The target is met by the blocks' exact reconstruction (the
// decoder's), never by the prediction: when corrections do not reach it, units fall back to
// threshold 0 (exact). Arrays too small to sample start from 1.5x (fixed rate) or 2.5x (variable rate) the MSE the target allows.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "pointdag/color/block_codec.h"

namespace pointdag {

struct TargetBlocks {
  std::vector<ColorBlock> blocks;  // sorted, covering every color, never across macro blocks
  std::vector<uint8_t> weights;    // every color's weight in its block, as ChooseBlockWeights picks it
  double max_mse = 0;              // the units' thresholds' geometric mean, by colors (exact units left out)
  double encodes = 0;              // colors encoded, in units of the whole array (the cost)
};

// `judged`: the indices the PSNR-Y is measured on (each below colors.size()); empty: all colors.
// `target`: dB, finite and positive. `hint`: a threshold to start from instead of the sample's
// prediction (positive and finite, else ignored). Errors only from EncodeBlocks (the device path).
StatusOr<TargetBlocks> BlocksForTarget(std::span<const Rgb8> colors, std::span<const uint64_t> judged, BlockLayout layout,
                                       double target, std::optional<double> hint = std::nullopt);

}  // namespace pointdag
