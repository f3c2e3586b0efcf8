#include "pointdag/color/block_codec.h"

#include <tbb/parallel_for.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <optional>
#include <string>

#include "pointdag/entropy/varint.h"

namespace pointdag {
namespace {

constexpr uint8_t kBlockStreamVersion = 1;
constexpr int kZstdLevel = 19;

struct Candidate {
  uint32_t start, length;
  BlockFit fit;
};

double Mse(const Candidate& c) { return c.fit.sse / (3.0 * c.length); }

// Paper IIA's merge passes, from the given blocks, at `bits` per weight.
std::vector<Candidate> MergePasses(std::span<const Rgb8> colors, std::vector<Candidate> blocks, int bits,
                                   double max_mse) {
  const auto fit = [&](uint32_t start, uint32_t length) {
    return Candidate{start, length, FitBlock(colors.data() + start, length, bits, max_mse * 3.0 * length)};
  };
  for (bool merged_any = true; merged_any;) {
    merged_any = false;
    std::vector<Candidate> out;
    std::vector<bool> merged;  // parallel to `out`: merged during this pass
    out.reserve(blocks.size());
    for (size_t i = 0; i < blocks.size(); ++i) {
      std::optional<Candidate> with_left, with_right;
      if (!out.empty() && !merged.back()) with_left = fit(out.back().start, out.back().length + blocks[i].length);
      if (i + 1 < blocks.size()) with_right = fit(blocks[i].start, blocks[i].length + blocks[i + 1].length);
      const bool left_ok = with_left && Mse(*with_left) <= max_mse;
      const bool right_ok = with_right && Mse(*with_right) <= max_mse;
      if (left_ok && (!right_ok || Mse(*with_left) <= Mse(*with_right))) {
        out.back() = *with_left;
        merged.back() = true;
        merged_any = true;
      } else if (right_ok) {
        out.push_back(*with_right);
        merged.push_back(true);
        merged_any = true;
        ++i;
      } else {
        out.push_back(blocks[i]);
        merged.push_back(false);
      }
    }
    blocks.swap(out);
  }
  return blocks;
}

std::vector<Candidate> Singletons(std::span<const Rgb8> colors, uint32_t begin, uint32_t end, int bits) {
  std::vector<Candidate> blocks;
  for (uint32_t i = begin; i < end; ++i) blocks.push_back({i, 1, FitBlock(colors.data() + i, 1, bits)});
  return blocks;
}

// Bits a block costs in the stored form before entropy coding: length, width, endpoints, weights.
double BlockCost(uint32_t length, int bits) { return 8 + 3 + (bits ? 48 : 24) + double(length) * bits; }

// Paper IIB: the block tree of one macro block (levels 0..4 bits) and its cheapest cut.
std::vector<ColorBlock> VariableRateMacroBlock(std::span<const Rgb8> colors, uint32_t begin, uint32_t end,
                                               double max_mse) {
  std::vector<std::vector<Candidate>> levels;
  levels.push_back(MergePasses(colors, Singletons(colors, begin, end, 0), 0, max_mse));
  for (int bits = 1; bits <= kMaxWeightBits; ++bits) {
    std::vector<Candidate> start;  // the previous level's blocks, refitted with more bits
    for (const Candidate& c : levels.back()) start.push_back({c.start, c.length, FitBlock(colors.data() + c.start, c.length, bits)});
    levels.push_back(MergePasses(colors, std::move(start), bits, max_mse));
  }
  // Cut bottom-up: best[level][k] is the cheapest way to code block k of that level.
  struct Best {
    double cost;
    bool keep_self;
  };
  std::vector<std::vector<Best>> best(levels.size());
  for (const Candidate& c : levels[0]) best[0].push_back({BlockCost(c.length, 0), true});
  for (size_t level = 1; level < levels.size(); ++level) {
    size_t child = 0;
    for (const Candidate& c : levels[level]) {
      double children = 0;
      for (; child < levels[level - 1].size() && levels[level - 1][child].start < c.start + c.length; ++child) {
        children += best[level - 1][child].cost;
      }
      const double own = BlockCost(c.length, static_cast<int>(level));
      best[level].push_back(own < children ? Best{own, true} : Best{children, false});
    }
  }
  // Expand the cut top-down over the ranges of the top level.
  std::vector<ColorBlock> out;
  const auto expand = [&](auto&& self, size_t level, uint32_t start, uint32_t stop) -> void {
    const auto& blocks = levels[level];
    auto it = std::lower_bound(blocks.begin(), blocks.end(), start, [](const Candidate& c, uint32_t s) { return c.start < s; });
    for (; it != blocks.end() && it->start < stop; ++it) {
      const size_t k = static_cast<size_t>(it - blocks.begin());
      if (best[level][k].keep_self) {
        out.push_back({it->start, it->length, static_cast<uint8_t>(level), it->fit.ends});
      } else {
        self(self, level - 1, it->start, it->start + it->length);
      }
    }
  };
  expand(expand, levels.size() - 1, begin, end);
  return out;
}

template <typename T>
void Put(std::vector<uint8_t>& out, T v) {
  const auto* p = reinterpret_cast<const uint8_t*>(&v);
  out.insert(out.end(), p, p + sizeof(T));
}

}  // namespace

std::vector<ColorBlock> EncodeBlocks(std::span<const Rgb8> colors, BlockLayout layout, double max_mse) {
  // Macro blocks are independent: encode them in parallel, concatenate in order.
  const size_t macros = (colors.size() + kMacroBlockColors - 1) / kMacroBlockColors;
  std::vector<std::vector<ColorBlock>> per_macro(macros);
  tbb::parallel_for(size_t{0}, macros, [&](size_t m) {
    const uint32_t begin = static_cast<uint32_t>(m * kMacroBlockColors);
    const uint32_t end = static_cast<uint32_t>(std::min<size_t>(colors.size(), size_t{begin} + kMacroBlockColors));
    if (layout == BlockLayout::kVariableRate) {
      per_macro[m] = VariableRateMacroBlock(colors, begin, end, max_mse);
    } else {
      for (const Candidate& c : MergePasses(colors, Singletons(colors, begin, end, kFixedRateBits), kFixedRateBits, max_mse)) {
        per_macro[m].push_back({c.start, c.length, kFixedRateBits, c.fit.ends});
      }
    }
  });
  std::vector<ColorBlock> blocks;
  for (const auto& macro : per_macro) blocks.insert(blocks.end(), macro.begin(), macro.end());
  return blocks;
}

StatusOr<std::vector<uint8_t>> SerializeBlocks(std::span<const Rgb8> colors, std::span<const ColorBlock> blocks,
                                               BlockLayout layout) {
  std::vector<uint8_t> body;
  Put<uint32_t>(body, static_cast<uint32_t>(colors.size()));
  Put<uint32_t>(body, static_cast<uint32_t>(blocks.size()));
  uint64_t next = 0;
  for (const ColorBlock& b : blocks) {
    if (b.start != next || b.length == 0 || b.bits > kMaxWeightBits) return Internal("color blocks do not tile the colors");
    next += b.length;
    PutVarint(body, b.length);
    if (layout == BlockLayout::kVariableRate) body.push_back(b.bits);
    body.insert(body.end(), {b.ends.a.r, b.ends.a.g, b.ends.a.b});
    if (b.bits) body.insert(body.end(), {b.ends.b.r, b.ends.b.g, b.ends.b.b});
  }
  if (next != colors.size()) return Internal("color blocks do not cover the colors");
  uint64_t acc = 0;
  int filled = 0;
  for (const ColorBlock& b : blocks) {
    for (uint32_t i = b.start; i < b.start + b.length && b.bits; ++i) {
      acc |= uint64_t{ChooseWeight(colors[i], b.ends, b.bits)} << filled;
      filled += b.bits;
      while (filled >= 8) {
        body.push_back(static_cast<uint8_t>(acc));
        acc >>= 8;
        filled -= 8;
      }
    }
  }
  if (filled > 0) body.push_back(static_cast<uint8_t>(acc));

  std::vector<uint8_t> out = {kBlockStreamVersion, static_cast<uint8_t>(layout), 0, 0};
  std::vector<uint8_t> z(ZSTD_compressBound(body.size()));
  const size_t n = ZSTD_compress(z.data(), z.size(), body.data(), body.size(), kZstdLevel);
  if (ZSTD_isError(n)) return Internal(std::string("zstd: ") + ZSTD_getErrorName(n));
  out.insert(out.end(), z.begin(), z.begin() + static_cast<long>(n));
  return out;
}

StatusOr<BlockColorDecoder> BlockColorDecoder::Open(std::span<const uint8_t> stored) {
  if (stored.size() < 4) return Truncated("color stream is shorter than its header");
  if (stored[0] != kBlockStreamVersion) return Corrupt("color stream version " + std::to_string(stored[0]) + " is unknown");
  const auto layout = static_cast<BlockLayout>(stored[1]);
  if (layout != BlockLayout::kFixedRate && layout != BlockLayout::kVariableRate) return Corrupt("color stream layout is unknown");
  const auto frame = stored.subspan(4);
  const unsigned long long size = ZSTD_getFrameContentSize(frame.data(), frame.size());
  // A color costs at most a 4-bit weight plus a whole block header (16 bytes is generous).
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN || size < 8) return Corrupt("color stream is not a zstd frame");
  if (size > (uint64_t{1} << 36)) return Corrupt("color stream declares an absurd size");
  std::vector<uint8_t> body;
  {
    // Grow with the data actually produced, so a lying frame header cannot force a huge allocation.
    std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
    ZSTD_inBuffer in = {frame.data(), frame.size(), 0};
    std::vector<uint8_t> chunk(ZSTD_DStreamOutSize());
    size_t last = 1;
    while (in.pos < in.size || last != 0) {
      ZSTD_outBuffer o = {chunk.data(), chunk.size(), 0};
      last = ZSTD_decompressStream(ctx.get(), &o, &in);
      if (ZSTD_isError(last)) return Corrupt("color stream fails to decompress");
      body.insert(body.end(), chunk.data(), chunk.data() + o.pos);
      if (body.size() > size) return Corrupt("color stream holds more than it declares");
      if (o.pos == 0 && in.pos == in.size && last != 0) return Truncated("color stream is cut short");
    }
  }
  if (body.size() != size) return Corrupt("color stream size disagrees with its frame header");

  BlockColorDecoder d;
  uint32_t count32, blocks32;
  std::memcpy(&count32, body.data(), 4);
  std::memcpy(&blocks32, body.data() + 4, 4);
  d.count_ = count32;
  if (blocks32 > count32 || (count32 > 0 && blocks32 == 0)) return Corrupt("color stream block count is impossible");
  size_t pos = 8;
  uint64_t next = 0, weight_bits = 0;
  for (uint32_t k = 0; k < blocks32; ++k) {
    uint64_t length;
    if (!GetVarint(body, pos, length) || length == 0 || length > count32 - next) return Corrupt("color block length is impossible");
    uint8_t bits = kFixedRateBits;
    if (layout == BlockLayout::kVariableRate) {
      if (pos >= body.size()) return Truncated("color block table is cut short");
      bits = body[pos++];
      if (bits > kMaxWeightBits) return Corrupt("color block has more than 4 bits per weight");
    }
    if (body.size() - pos < (bits ? 6u : 3u)) return Truncated("color block table is cut short");
    Endpoints e;
    e.a = {body[pos], body[pos + 1], body[pos + 2]};
    e.b = bits ? Rgb8{body[pos + 3], body[pos + 4], body[pos + 5]} : e.a;
    pos += bits ? 6 : 3;
    if (next / kMacroBlockColors != (next + length - 1) / kMacroBlockColors) return Corrupt("color block crosses a macro block");
    d.starts_.push_back(static_cast<uint32_t>(next));
    d.weight_offsets_.push_back(weight_bits);
    d.bits_.push_back(bits);
    d.ends_.push_back(e);
    next += length;
    weight_bits += length * bits;
  }
  if (next != count32) return Corrupt("color blocks do not cover every color");
  if (body.size() - pos != (weight_bits + 7) / 8) return Corrupt("color weights have the wrong size");
  d.weights_.assign((weight_bits + 63) / 64 + 1, 0);
  std::memcpy(d.weights_.data(), body.data() + pos, body.size() - pos);
  // Macro-block table: the first block of every macro block.
  const uint64_t macros = (d.count_ + kMacroBlockColors - 1) / kMacroBlockColors;
  for (uint64_t m = 0, k = 0; m <= macros; ++m) {
    while (k < d.starts_.size() && d.starts_[k] < m * kMacroBlockColors) ++k;
    d.macro_first_block_.push_back(static_cast<uint32_t>(k));
  }
  return d;
}

uint32_t BlockColorDecoder::Weight(uint64_t bit_offset, int bits) const {
  const uint64_t word = bit_offset >> 6;
  const unsigned shift = bit_offset & 63;
  uint64_t v = weights_[word] >> shift;
  if (shift + static_cast<unsigned>(bits) > 64) v |= weights_[word + 1] << (64 - shift);
  return static_cast<uint32_t>(v & ((1u << bits) - 1));
}

Rgb8 BlockColorDecoder::FromBlock(size_t block, uint64_t index) const {
  const int bits = bits_[block];
  if (bits == 0) return ends_[block].a;
  return Interpolate(ends_[block], Weight(weight_offsets_[block] + (index - starts_[block]) * bits, bits), bits);
}

Rgb8 BlockColorDecoder::At(uint64_t index) const {
  const uint64_t macro = index / kMacroBlockColors;
  const auto first = starts_.begin() + macro_first_block_[macro];
  const auto last = starts_.begin() + macro_first_block_[macro + 1];
  const auto it = std::upper_bound(first, last, static_cast<uint32_t>(index));
  return FromBlock(static_cast<size_t>(it - starts_.begin()) - 1, index);
}

void BlockColorDecoder::Decode(uint64_t begin, uint64_t end, Rgb8* out) const {
  if (begin >= end) return;
  size_t block = static_cast<size_t>(std::upper_bound(starts_.begin(), starts_.end(), static_cast<uint32_t>(begin)) - starts_.begin()) - 1;
  for (uint64_t i = begin; i < end; ++i) {
    while (block + 1 < starts_.size() && starts_[block + 1] <= i) ++block;
    *out++ = FromBlock(block, i);
  }
}

std::vector<Rgb8> BlockColorDecoder::DecodeAll() const {
  std::vector<Rgb8> colors(count_);
  Decode(0, count_, colors.data());
  return colors;
}

size_t BlockColorDecoder::ResidentBytes() const {
  return starts_.size() * (4 + 8 + 1 + sizeof(Endpoints)) + macro_first_block_.size() * 4 + weights_.size() * 8;
}

}  // namespace pointdag
