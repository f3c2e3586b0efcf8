// The block color stream's shared definitions (proto/PDAG_FORMAT.md §3), used by its writer
// (SerializeBlocks, block_codec.cc) and its reader (BlockColorDecoder, block_decoder.cc).
#pragma once

#include <array>
#include <bit>
#include <cstdint>

#include "pointdag/color/block_codec.h"
#include "pointdag/entropy/adaptive_codes.h"

namespace pointdag {

constexpr uint8_t kBlockStreamVersion = 1;

// Models of the block stream. Contexts: the previous block's width for lengths and widths; the
// channel for endpoint differences (and the width for B - A); the width and the previous weight of
// the same block for weights, since Morton neighbours tend to sit at the same point of a gradient.
struct BlockModels {
  std::array<GammaModel, kMaxWeightBits + 1> length;
  std::array<BitTreeModel<3>, kMaxWeightBits + 1> width;
  std::array<GammaModel, 3> a;
  std::array<std::array<GammaModel, 3>, kMaxWeightBits + 1> b;
  std::array<std::array<BitTreeModel<kMaxWeightBits>, 17>, kMaxWeightBits + 1> weight;  // 16 = first of a block
};

constexpr int kLengthBits = std::bit_width(kMacroBlockColors);
constexpr int kDifferenceBits = 9;  // zigzag of -255..255, plus one

}  // namespace pointdag
