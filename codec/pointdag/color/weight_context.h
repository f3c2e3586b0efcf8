// Spatial contexts for the block color stream's weights (stream versions 3 and 4, leaf mode;
// proto/PDAG_FORMAT.md §3), shared by its writer (SerializeBlocks) and reader (BlockColorDecoder::Open).
// Version 4 also takes the position in half steps (weight_mixer.h) and predicts a block's endpoint A
// from the decoded neighbours around its first voxels (Surroundings; PredictA in block_stream.h).
//
// Colors are one per voxel in Morton order, so of a voxel's 26 face, edge and corner neighbours
// those with a lower Morton code are decoded before it. The mean of their decoded colors (faces
// weigh 4, edges 2, corners 1) is projected onto the segment of the current block (A to B) and
// rounded to its weight steps: that is the context. Inside the block it is about the neighbours' own
// weights; in another block it still says where their colors lie between this block's A and B,
// which that block's weights would not. A voxel with none of them takes the block's previous
// weight as its context, as in version 2. Measured on the weights of lion 1 cm, guanyin 2 mm and
// autzen 4 ft at 38 dB: 8-10 % fewer weight bits; the face neighbours alone gave 3-4 %, a 5x5x5
// neighbourhood no more than 3x3x3, the neighbours' spread or count as a second context less, the
// mean of each neighbour's own clamped step the same.
//
// Neighbours are found through the voxels' 4x4x4 bricks (voxel_bricks.h): the bricks around the
// current one are looked up once per brick, and which cells a voxel's preceding neighbours are
// comes from a table per cell. Whole-file decode of lion 1 cm at 38 dB (DecodePdag, one core):
// version 2 52 ms; version 3 with a hash table of the voxels' codes 114 ms, with bricks 106, with
// the table and one projection per weight (not per neighbour) 88. Version 4 walks the bricks twice
// (the endpoints' walk runs ahead of the weights'), sharing the bricks entered (entered_ below).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/color/block_fit.h"
#include "pointdag/color/voxel_bricks.h"

namespace pointdag {

// Contexts per weight width: 0..15 the neighbours' mean position, 16 + previous weight (0..16,
// 16 = the first of a block) without neighbours.
constexpr int kSpatialWeightContexts = 33;

// Where the decoded neighbours' mean color lies on a block's segment A -> B, rounded to its weight
// steps (0..m, m = 2^bits - 1) and to half steps (0..2m); `found` false without such neighbours,
// `far` where they are the cells two away (none of the 26 around precedes).
struct NeighbourPosition {
  bool found = false, far = false;
  uint32_t step = 0, half_step = 0;
};

// The neighbours that precede a block (stream version 4's endpoint prediction): the weighted sum
// of their decoded colors and of their weights, each neighbour counted once per voxel of the block
// it touches (the block's first kPredictingVoxels voxels).
struct BlockSurroundings {
  int64_t r = 0, g = 0, b = 0, weight = 0;
};
constexpr uint32_t kPredictingVoxels = 64;

class WeightContexts {
 public:
  // `morton`: one code per color, sorted and unique (as decoded geometry enumerates the voxels);
  // must outlive this object.
  explicit WeightContexts(std::span<const uint64_t> morton);

  // Where color i's preceding neighbours lie on the segment of a block of `ends` and `bits` (1..4)
  // per weight; with `far`, where none of the 26 around it precedes it, the preceding cells two
  // away (version 4). Colors before i must be recorded; i never decreases from one call to the next.
  NeighbourPosition Position(uint64_t i, const Endpoints& ends, int bits, bool far);
  // Version 3's context of color i's weight: Position's step, else 16 + `prev`, the previous weight
  // of the same block (16 at its first).
  uint32_t Of(uint64_t i, const Endpoints& ends, int bits, uint32_t prev) {
    const NeighbourPosition p = Position(i, ends, bits, false);
    return p.found ? p.step : 16 + prev;
  }
  // The decoded neighbours of the block of colors [start, start + length) that precede it. Colors
  // before `start` must be recorded; `start` never decreases from one call to the next, and is at
  // least the last Position's i.
  BlockSurroundings Surroundings(uint64_t start, uint32_t length);
  // Color i as decoded.
  void Record(uint64_t i, const Rgb8& c) { decoded_[i] = c.r | uint64_t{c.g} << 16 | uint64_t{c.b} << 32 | kOne; }

 private:
  // Brick `brick`'s neighbour bricks that precede it (and itself), by offset (dx + 1) * 9 + (dy + 1)
  // * 3 + dz + 1 (its slot), with an empty mask elsewhere.
  using Near = std::array<VoxelBrick, 27>;
  struct Entered {
    size_t brick = SIZE_MAX;
    Near near{};
  };
  // Moves a walk forward through the bricks (`cursor`: a brick index) to color i's brick, and returns
  // its neighbours. Weights and endpoints each walk with their own cursor.
  const Near& Seek(size_t& cursor, uint64_t i);
  void EnterBrick(Entered& entry, size_t k);
  // The weighted sum of the packed colors (below) of color i's neighbours in `table` (of a cell's
  // neighbour groups by its bit in the brick) that precede it, with kBelowOnly those before `below`.
  template <bool kBelowOnly, typename Table>
  uint64_t PrecedingSum(const Table& table, const Near& near, uint64_t i, uint64_t below) const;

  // Decoded colors packed as r | g << 16 | b << 32 | 1 << 48, so that a neighbour's weighted color
  // and its weight add up in one multiply-add: no lane of a sum overflows (at most 255 x 124, the
  // largest total weight, the cells two away, each in 16 bits). With Position's 32-bit division:
  // the weight contexts of a lion 1 cm decode at 38 dB 185 -> 172 M instructions.
  static constexpr uint64_t kOne = uint64_t{1} << 48;
  std::span<const uint64_t> morton_;
  std::vector<uint64_t> decoded_;
  VoxelBricks bricks_;
  size_t weights_ = 0, ends_ = 0;
  // The bricks entered, by brick index & entered_mask_ (up to 128 of them): the endpoints' walk runs
  // at most 64 voxels, so 64 bricks, ahead of the weights', so each walk finds the bricks the other
  // entered; Seek checks the slot, so a walk that fell behind (0-bit blocks have no weights) enters
  // its brick again. Guanyin 2 mm at 38 dB, decode: the weight contexts 183 -> 172 M instructions
  // (the 8 bricks last entered, copied into each walk, had it find 59.6 k bricks' neighbours; now 54.4 k).
  std::vector<Entered> entered_;
  size_t entered_mask_ = 0;
};

}  // namespace pointdag
