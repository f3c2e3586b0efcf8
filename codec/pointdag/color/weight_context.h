// Spatial contexts for the block color stream's weights (stream version 3, leaf mode;
// proto/PDAG_FORMAT.md §3), shared by its writer (SerializeBlocks) and reader (BlockColorDecoder::Open).
//
// Colors are one per voxel in Morton order, so of a voxel's 26 face, edge and corner neighbours
// those with a lower Morton code are decoded before it. Their decoded colors are projected onto the
// segment of the current block (A to B) and rounded to its weight steps: inside the block that is the
// neighbour's own weight; in another block it still says where the neighbour's color lies between
// this block's A and B, which that block's weight would not. The context is the mean of those
// positions (faces weigh 4, edges 2, corners 1), or, for a voxel with none of them, the block's
// previous weight as in version 2. Measured on the weights of lion 1 cm, guanyin 2 mm and autzen
// 4 ft at 38 dB: 8-10 % fewer weight bits; the face neighbours alone gave 3-4 %, a 5x5x5 neighbourhood
// no more than 3x3x3, the neighbours' spread or count as a second context less.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/color/block_fit.h"
#include "pointdag/color/morton_table.h"

namespace pointdag {

// Contexts per weight width: 0..15 the neighbours' mean position, 16 + previous weight (0..16,
// 16 = the first of a block) without neighbours.
constexpr int kSpatialWeightContexts = 33;

class WeightContexts {
 public:
  // `morton`: one code per color, sorted and unique (as decoded geometry enumerates the voxels);
  // must outlive this object.
  explicit WeightContexts(std::span<const uint64_t> morton);

  // The context of color i's weight in a block of `ends` and `bits` (1..4) per weight, `prev` the
  // previous weight of the same block (16 at its first). Colors before i must be recorded.
  uint32_t Of(uint64_t i, const Endpoints& ends, int bits, uint32_t prev) const;
  // Color i as decoded.
  void Record(uint64_t i, const Rgb8& c) { decoded_[i] = c; }

 private:
  std::span<const uint64_t> morton_;
  MortonTable table_;
  std::vector<Rgb8> decoded_;
};

}  // namespace pointdag
