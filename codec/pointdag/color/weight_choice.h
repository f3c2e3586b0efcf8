// Encoder only: the weights a block's colors are stored with, chosen for error and rate together.
//
// The weights of a block together minimize the sum of BlockError + price * (estimated bits of each
// weight after the block's previous one), each weight within one step of the error-minimizing one
// (ChooseWeight; a Viterbi search). The estimate is a static table of what the stream's adaptive
// weight models (their context: the previous weight) learn, so that a block's weights depend on
// that block alone: the threshold search (block_target.cc) measures the same
// reconstruction the serializer stores and the decoder rebuilds. Price 0: every weight is
// ChooseWeight's (the error-minimizing choice of stream versions 1 and 2's first writer).
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

// The weights of block `b` for colors [b.start, b.start + b.length) into out[0, b.length), each in
// 0..2^b.bits - 1 (all 0 for 0-bit blocks). `colors` is the whole array the block indexes.
void ChooseBlockWeights(std::span<const Rgb8> colors, const ColorBlock& b, std::span<uint8_t> out);

}  // namespace pointdag
