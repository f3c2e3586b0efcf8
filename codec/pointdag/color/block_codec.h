// Stage 5b: palette-free block color codecs (Papers IIA and IIB), paired encoder/decoder.
//
// Colors are in color-index order (Morton order of the voxels, or DAG pre-order for mipmaps), which
// keeps neighbours in space neighbours in the array. The array is cut into macro blocks of 16384
// colors, coded independently (Paper IIB; we apply it to the fixed-rate codec too, so that both
// share one decoder and every macro block can be encoded on its own, e.g. by one GPU workgroup).
//
// Fixed rate (IIA): every color gets a 3-bit weight. Encoding starts from one block per color; each
// pass walks the blocks and merges each with its right neighbour where the merged block stays within
// the threshold; a block merges at most once per pass; passes repeat until one merges nothing.
// Variable rate (IIB): the same merge passes with 0 bits per weight give the tree's leaves; merging
// those with 2 bits gives their parents, and so on up to 4 bits (the 1-bit level keeps the leaves
// unmerged: block_codec.cc, kFirstMergedBits). Here the threshold prices bits instead of bounding
// errors: a merge is kept where the error it adds is worth less than the header it saves, and the
// tree is cut bottom-up, keeping a node only where its error plus its bits cost less than its
// children's. All of it is integer arithmetic, so that the Vulkan port (gpu/shaders/block_*.comp)
// returns the same blocks.
//
// Decoding one color touches one macro-block entry, a binary search over that macro block's block
// starts, and one weight: no other block is read.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/color/block_fit.h"
#include "pointdag/status.h"

namespace pointdag::gpu {
class VulkanContext;
}

namespace pointdag {

constexpr uint32_t kMacroBlockColors = 16384;
constexpr int kFixedRateBits = 3;

struct ColorBlock {
  uint32_t start = 0;   // index of its first color
  uint32_t length = 0;
  uint8_t bits = 0;     // bits per weight, 0..4
  Endpoints ends;
  // What a bit of weights is worth in BlockError units when the encoder chooses them (weight_choice.h);
  // 0: each weight minimizes its own error. Not stored: the stream holds the weights chosen.
  uint32_t rate_price = 0;
};

enum class BlockLayout : uint8_t { kFixedRate = 1, kVariableRate = 2 };

// `max_mse` bounds each fixed-rate block's mean luma-weighted error per channel (BlockError / 3,
// block_fit.h; the RGB squared error for gray differences), and prices a variable-rate block's
// bits (1536 max_mse BlockError units a bit, block_codec.cc); 0 keeps every color exact where the
// model allows. Blocks come out sorted, covering every color once, never across macro blocks.
// Runs on Vulkan where ColorBlocksDevice() says so, with the same result; an error only from there
// (POINTDAG_DEVICE unknown, or `vulkan` without a device, or the device failing).
StatusOr<std::vector<ColorBlock>> EncodeBlocks(std::span<const Rgb8> colors, BlockLayout layout, double max_mse);

// Where EncodeBlocks runs in this process (null: the CPU), per gpu/pointdag/gpu/stage_device.h;
// under POINTDAG_DEVICE=auto decided on the first call by timing both paths.
StatusOr<gpu::VulkanContext*> ColorBlocksDevice();

// The stored form: block table and weights, range-coded with adaptive models
// (layout: proto/PDAG_FORMAT.md §3). `morton`: the voxels' Morton codes when `colors` are one per
// voxel in Morton order (leaf mode; sorted, unique), which give the weights spatial contexts and
// endpoint A a prediction from the decoded neighbours (stream version 4), else empty (version 2).
// `decoded`, when given, receives the colors the stream decodes to (BlockColorDecoder's, the writer
// rebuilds them as it goes), so that an encoder measures them without decoding the stream again.
// `weights`, when given (one per color), are ChooseBlockWeights' weights of every block, already
// chosen (TargetBlocks::weights); else the writer chooses them.
StatusOr<std::vector<uint8_t>> SerializeBlocks(std::span<const Rgb8> colors, std::span<const ColorBlock> blocks,
                                               BlockLayout layout, std::span<const uint64_t> morton = {},
                                               std::vector<Rgb8>* decoded = nullptr, std::span<const uint8_t> weights = {});

// Resident form for random access and batch decoding.
class BlockColorDecoder {
 public:
  // `expected_count`: how many colors the caller knows there are (bounds every allocation).
  // `morton`: as for SerializeBlocks; a version 3 or 4 stream is kCorrupt without them (count of them).
  // They only steer the entropy decode here: once open, a color decodes without its neighbours.
  static StatusOr<BlockColorDecoder> Open(std::span<const uint8_t> stored, uint64_t expected_count,
                                          std::span<const uint64_t> morton = {});

  uint64_t size() const { return count_; }
  size_t block_count() const { return starts_.size(); }
  Rgb8 At(uint64_t index) const;                            // index < size()
  void Decode(uint64_t begin, uint64_t end, Rgb8* out) const;  // colors [begin, end)
  std::vector<Rgb8> DecodeAll() const;
  size_t ResidentBytes() const;
  // A block's weight width and its weights, one per color (inspection, e.g. tools/weight_codes_trainer.cc).
  int BlockBits(size_t block) const { return bits_[block]; }
  std::vector<uint8_t> BlockWeights(size_t block) const;

 private:
  uint32_t Weight(uint64_t bit_offset, int bits) const;
  Rgb8 FromBlock(size_t block, uint64_t index) const;

  uint64_t count_ = 0;
  std::vector<uint32_t> starts_;
  std::vector<uint64_t> weight_offsets_;  // bit offset of each block's first weight
  std::vector<uint8_t> bits_;
  std::vector<Endpoints> ends_;
  std::vector<uint32_t> macro_first_block_;  // per macro block, plus one past the end
  std::vector<uint64_t> weights_;            // packed LSB-first, with one word of padding
};

}  // namespace pointdag
