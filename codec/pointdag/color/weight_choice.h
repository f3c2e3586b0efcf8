// Encoder only: the weights a block's colors are stored with, chosen for error and rate together.
//
// The weights of a block together minimize the sum of BlockError + price * (estimated bits of each
// weight after the block's previous one), each weight within one step of the error-minimizing one
// (ChooseWeight; a Viterbi search). The estimate is a static table of what a weight costs in stream
// version 3 by its distance to the previous one (the true context, the neighbours' colors, lies in
// other blocks), so that a block's weights depend on that block alone (a table by the distance to
// the neighbours' step as well, the neighbours' colors taken as given, measured no smaller under
// version 4's mixer: docs/benchmarks.md): the threshold search
// (block_target.cc) measures the same
// reconstruction the serializer stores and the decoder rebuilds. Price 0: every weight is
// ChooseWeight's (the error-minimizing choice of stream versions 1 and 2's first writer). The
// search also refits a priced block's endpoints for the weights chosen (RefitEnds), after the
// blocks are made: the merges, the cut and their Vulkan port are unchanged.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "pointdag/color/block_codec.h"

namespace pointdag {

// The price the threshold search (block_target.cc) gives blocks encoded at `max_mse` for an array
// of `array_colors`: BlockError units (1/1024ths) per bit of weights. 0 for arrays under a macro
// block, whose weight models stay too young for the estimate (tiny at 8 ft grew up to 7 %).
uint32_t WeightRatePrice(double max_mse, size_t array_colors);

// The weights of block `b` for colors [b.start, b.length) into out[0, b.length), each in
// 0..2^b.bits - 1 (all 0 for 0-bit blocks). `colors` is the whole array the block indexes. Returns
// the cost they minimize, 16 x BlockError summed + price x estimated bits in 1/16ths (0 unpriced).
uint64_t ChooseBlockWeights(std::span<const Rgb8> colors, const ColorBlock& b, std::span<uint8_t> out);

// The fitter placed b's endpoints for the error-minimizing weights (and kept unrefined ones where
// they passed well: block_fit.h); for a priced block, fits them again by least squares for the
// weights ChooseBlockWeights picks and keeps them where that lowers its cost. A priced block only.
// `weights` (b.length of them) ends with ChooseBlockWeights' weights for b as it leaves, so that
// callers measuring or writing the block need not choose them again.
void RefitEnds(std::span<const Rgb8> colors, ColorBlock& b, std::span<uint8_t> weights);

}  // namespace pointdag
