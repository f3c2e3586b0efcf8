// The block color stream's shared definitions (proto/PDAG_FORMAT.md §3), used by its writer
// (SerializeBlocks, block_codec.cc) and its reader (BlockColorDecoder, block_decoder.cc).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/color/block_codec.h"
#include "pointdag/color/weight_context.h"
#include "pointdag/entropy/adaptive_codes.h"

namespace pointdag {

// Version 2 codes the endpoint differences decorrelated (DifferenceCode below); version 3 (leaf mode,
// colors one per voxel in Morton order) codes the weights with spatial contexts (weight_context.h);
// version 4 (leaf mode) mixes four models per weight bit (weight_mixer.h) and predicts endpoint A
// from the block's decoded neighbours (PredictA below); version 6 (tiles, which every client decodes
// on every view) is version 2 with its weights in groups, each read by one lookup in a prefix code
// fixed in the format (prefix_weights.h, fixed_weight_codes.h). Version 5 was never released and is
// refused. Files write version 4 (with the voxels' Morton codes) or 2 (mipmap colors, whose order is
// not the voxels'); tiles write version 6 (TilingOptions); 1 and 3 are still read.
constexpr uint8_t kBlockStreamVersion = 6;  // the newest
constexpr uint8_t kPlainVersion = 2;
constexpr uint8_t kMixedVersion = 4;
constexpr uint8_t kFixedWeightCodesVersion = 6;
constexpr bool IsBlockStreamVersion(uint8_t version) { return version >= 1 && version <= kBlockStreamVersion && version != 5; }
constexpr bool HasSpatialContexts(uint8_t version) { return version == 3 || version == kMixedVersion; }

// Models of the block stream. Contexts: the previous block's width for lengths and widths; the
// component for endpoint differences (and the width for B - A; version 4: whether A is predicted from
// the block's neighbours or from the previous block's A); the width and, for weights, the
// previous weight of the same block (versions 1 and 2: 0..16, 16 = first of a block), since Morton
// neighbours tend to sit at the same point of a gradient, or the spatial context (version 3:
// 0..kSpatialWeightContexts - 1); version 4 codes weights with its own models (WeightMixer).
struct BlockModels {
  std::array<GammaModel, kMaxWeightBits + 1> length;
  std::array<BitTreeModel<3>, kMaxWeightBits + 1> width;
  std::array<GammaModel, 3> a;
  std::array<GammaModel, 3> a_near;
  std::array<std::array<GammaModel, 3>, kMaxWeightBits + 1> b;
  std::array<std::array<BitTreeModel<kMaxWeightBits>, kSpatialWeightContexts>, kMaxWeightBits + 1> weight;
};

constexpr int kLengthBits = std::bit_width(kMacroBlockColors);

// An endpoint difference d = (dR, dG, dB) (A from the previous block's A, or B from A) as the three
// components the stream codes. Version 1: the channels themselves, each in -255..255. Version 2:
// (dG, dR - dG, dB - dG): colors move mostly along gray, so the channels' differences share most of
// their size and the last two components are small (measured: endpoints 5-21 % fewer bits than
// version 1 on lion, guanyin and autzen at 34-42 dB; YCoCg-R did as well, contexts by the previous
// residual's size did worse).
struct DifferenceCode {
  bool decorrelated;
  // Bit width of the largest zigzag value of a component (-510..510 in version 2).
  int MaxBits() const { return decorrelated ? 10 : 9; }
  std::array<int, 3> Components(int dr, int dg, int db) const {
    return decorrelated ? std::array<int, 3>{dg, dr - dg, db - dg} : std::array<int, 3>{dr, dg, db};
  }
  // The difference (dR, dG, dB) from its components.
  std::array<int, 3> Channels(const std::array<int, 3>& c) const {
    return decorrelated ? std::array<int, 3>{c[1] + c[0], c[0], c[2] + c[0]} : c;
  }
};

// Version 4's prediction of a block's endpoint A where decoded neighbours precede it (s.weight > 0):
// their weighted mean color, less half of B - A (`span`, zero for 0-bit blocks) per channel, so
// that the segment's middle lands on the mean (halves rounded toward zero), clamped to 0..255.
// Measured on lion, guanyin and autzen at 34-42 dB: A's bits 11-15 % below version 3's prediction
// from the previous block's A (the neighbours of all of a block's voxels rather than its first 64:
// under 0.1 % of the stream smaller; the first voxel's alone: half the gain; A itself predicted
// rather than the middle, with version 3's models: half; models by the neighbours' spread: less).
inline std::array<int, 3> PredictA(const BlockSurroundings& s, const std::array<int, 3>& span) {
  const int64_t sums[3] = {s.r, s.g, s.b};
  std::array<int, 3> p{};
  for (int c = 0; c < 3; ++c) p[c] = std::clamp(static_cast<int>((sums[c] + s.weight / 2) / s.weight) - span[c] / 2, 0, 255);
  return p;
}

// SerializeBlocks writing the given stream version (1..4 or 6; 3 and 4 need `morton`): older
// versions stay writable so that tests can check they still decode.
StatusOr<std::vector<uint8_t>> SerializeBlocksAsVersion(std::span<const Rgb8> colors, std::span<const ColorBlock> blocks,
                                                        BlockLayout layout, uint8_t version,
                                                        std::span<const uint64_t> morton = {},
                                                        std::vector<Rgb8>* decoded = nullptr,
                                                        std::span<const uint8_t> weights = {});

}  // namespace pointdag
