// BlockColorDecoder (declared in block_codec.h): the reader of the block color stream, apart from
// the encoder so that a decoder-only build (the WebAssembly one, web/wasm) needs neither TBB nor Vulkan.
#include <algorithm>
#include <array>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "pointdag/color/block_stream.h"
#include "pointdag/color/fixed_weight_codes.h"
#include "pointdag/color/prefix_weights.h"
#include "pointdag/color/weight_mixer.h"
#include "pointdag/entropy/varint.h"

namespace pointdag {
namespace {

uint32_t PackedWeight(const uint64_t* words, uint64_t bit_offset, int bits) {
  const uint64_t word = bit_offset >> 6;
  const unsigned shift = bit_offset & 63;
  uint64_t v = words[word] >> shift;
  if (shift + static_cast<unsigned>(bits) > 64) v |= words[word + 1] << (64 - shift);
  return static_cast<uint32_t>(v & ((1u << bits) - 1));
}

// `n` colors of one block from its weights at `bit_offset`, kBits a constant so that Interpolate
// divides by a constant (a multiply) and the weight reads need no variable masks.
// A run longer than the block's 2^kBits colors looks them up, interpolated once each.
template <int kBits>
void DecodeRun(const Endpoints& ends, const uint64_t* words, uint64_t bit_offset, uint64_t n, Rgb8* out) {
  constexpr uint32_t kColors = 1u << kBits;
  if (n <= kColors) {
    for (uint64_t i = 0; i < n; ++i, bit_offset += kBits) out[i] = Interpolate(ends, PackedWeight(words, bit_offset, kBits), kBits);
    return;
  }
  std::array<Rgb8, kColors> palette;
  for (uint32_t w = 0; w < kColors; ++w) palette[w] = Interpolate(ends, w, kBits);
  uint64_t i = 0;
  if constexpr (64 % kBits == 0) {
    // Whole words of weights, each loaded once (a width that divides 64 never straddles them once
    // the offset is word-aligned).
    for (; i < n && (bit_offset & 63); ++i, bit_offset += kBits) out[i] = palette[PackedWeight(words, bit_offset, kBits)];
    constexpr uint64_t kPerWord = 64 / kBits;
    for (; i + kPerWord <= n; i += kPerWord, bit_offset += 64) {
      const uint64_t word = words[bit_offset >> 6];
#pragma GCC unroll 64
      for (uint64_t j = 0; j < kPerWord; ++j) out[i + j] = palette[(word >> (j * kBits)) & (kColors - 1)];
    }
  }
  for (; i < n; ++i, bit_offset += kBits) out[i] = palette[PackedWeight(words, bit_offset, kBits)];
}

// Weights with the previous weight as their only context (versions 1 and 2, and mipmapped
// streams of any version: no Morton codes, no spatial contexts), kBits a constant so that each
// bit tree unrolls. Writes them packed at `bit_offset` into `words` (sized by the caller).
template <int kBits>
void DecodePlainWeights(BinaryRangeDecoder& rc, std::span<BitTreeModel<kMaxWeightBits>> models, uint32_t length,
                        uint64_t* words, uint64_t bit_offset) {
  uint32_t prev = 16;
  // The word being filled stays in a register: one store per 64 bits.
  uint64_t* word = words + (bit_offset >> 6);
  unsigned used = bit_offset & 63;
  uint64_t pending = *word;  // the bits below `used` are earlier blocks'
  for (uint32_t i = 0; i < length; ++i) {
    BitTreeModel<kMaxWeightBits>& m = models[prev];
    uint32_t node = 1;
#pragma GCC unroll 4
    for (int b = 0; b < kBits; ++b) node = node << 1 | static_cast<uint32_t>(rc.Decode(m.node[node]));
    const uint32_t w = node - (1u << kBits);
    pending |= uint64_t{w} << used;
    used += kBits;
    if (used >= 64) {
      *word++ = pending;
      used -= 64;
      pending = used ? uint64_t{w} >> (kBits - used) : 0;
    }
    prev = w;
  }
  *word = pending;
}

}  // namespace

StatusOr<BlockColorDecoder> BlockColorDecoder::Open(std::span<const uint8_t> stored, uint64_t expected_count,
                                                    std::span<const uint64_t> morton) {
  if (stored.size() < 4) return Truncated("color stream is shorter than its header");
  if (!IsBlockStreamVersion(stored[0])) return Corrupt("color stream version " + std::to_string(stored[0]) + " is unknown");
  const DifferenceCode code{stored[0] >= 2};
  const bool mixed = stored[0] == kMixedVersion;
  const bool grouped = stored[0] == kFixedWeightCodesVersion;
  const auto layout = static_cast<BlockLayout>(stored[1]);
  if (layout != BlockLayout::kFixedRate && layout != BlockLayout::kVariableRate) return Corrupt("color stream layout is unknown");
  size_t pos = 4;
  uint64_t count = 0, blocks = 0;
  uint64_t payload_size = 0;
  if (!GetVarint(stored, pos, count) || !GetVarint(stored, pos, blocks) || !GetVarint(stored, pos, payload_size)) {
    return Truncated("color stream header is cut short");
  }
  if (payload_size != stored.size() - pos) return Truncated("color stream is not as long as its header says");
  if (count != expected_count) return Corrupt("color stream holds " + std::to_string(count) + " colors, expected " + std::to_string(expected_count));
  if (count > 0xFFFFFFFFull || blocks > count || (count > 0 && blocks == 0)) return Corrupt("color stream block count is impossible");
  const bool spatial_contexts = HasSpatialContexts(stored[0]);
  if (spatial_contexts && morton.size() != count) {
    return Corrupt("color stream has spatial contexts, but there are no voxels' Morton codes for them");
  }
  // A block of 16384 colors costs at least 11 raw bits of its length's gamma code, and no block
  // covers more colors per bit: a byte of payload holds less than one macro block of colors.
  if (count / kMacroBlockColors > payload_size + 8) {
    return Corrupt("color stream declares " + std::to_string(count) + " colors, more than its " +
                   std::to_string(payload_size) + " bytes can hold");
  }

  BlockColorDecoder d;
  d.count_ = count;
  // After the checks above: it allocates by `count`, which the caller's Morton codes bear out.
  std::optional<WeightContexts> spatial;
  if (spatial_contexts) spatial.emplace(morton);
  // Default-initialized (new T, not make_unique's new T(); emscripten's libc++ lacks
  // make_unique_for_overwrite): every model starts at its own initializer; make_unique would zero the
  // 41 KB first (a memset that was 5 % of a small tile's decode).
  std::unique_ptr<BlockModels> models(new BlockModels);
  std::optional<WeightMixer> mixer;
  if (mixed) mixer.emplace();
  // Version 6: the range-coded section's length, the section, then the weights' groups.
  std::span<const uint8_t> ranged = stored.subspan(pos), group_bytes;
  if (grouped) {
    size_t at = 0;
    uint64_t ranged_size = 0;
    if (!GetVarint(ranged, at, ranged_size)) return Truncated("color stream ends inside its section length");
    if (ranged_size > ranged.size() - at) return Truncated("color stream is shorter than its section length says");
    group_bytes = ranged.subspan(at + ranged_size);
    ranged = ranged.subspan(at, ranged_size);
  }
  BinaryRangeDecoder rc(ranged);
  PrefixDecoder groups(group_bytes);
  const FixedWeightCodes* codes = grouped ? &FixedWeightGroupCodes() : nullptr;
  // An endpoint difference (dR, dG, dB) from its three coded components.
  const auto decode_difference = [&](std::array<GammaModel, 3>& m) {
    std::array<int, 3> components{};
    for (int c = 0; c < 3; ++c) components[c] = UnZigZag(DecodeGamma(rc, m[c], code.MaxBits()));
    return code.Channels(components);
  };
  uint64_t next = 0, weight_bits = 0;
  int prev_bits = 0;
  Rgb8 prev_a{};
  d.weights_.assign(2, 0);  // grows with the weights really decoded, plus one word of padding
  // Bounded by `count`, which the caller knows: its colors take more than these.
  d.starts_.reserve(blocks);
  d.weight_offsets_.reserve(blocks);
  d.bits_.reserve(blocks);
  d.ends_.reserve(blocks);
  for (uint64_t k = 0; k < blocks; ++k) {
    const uint32_t length = DecodeGamma(rc, models->length[prev_bits], kLengthBits);
    const int bits = layout == BlockLayout::kVariableRate ? static_cast<int>(DecodeBitTree<3>(rc, models->width[prev_bits]))
                                                          : kFixedRateBits;
    if (bits > kMaxWeightBits) return Corrupt("color block has more than 4 bits per weight");
    if (length == 0 || length > count - next) return Corrupt("color block length is impossible");
    if (next / kMacroBlockColors != (next + length - 1) / kMacroBlockColors) return Corrupt("color block crosses a macro block");
    std::array<int, 3> base = {prev_a.r, prev_a.g, prev_a.b}, da{}, de{};  // A - base, B - A
    if (mixed) {
      if (bits) de = decode_difference(models->b[bits]);
      const BlockSurroundings near = spatial->Surroundings(next, length);
      if (near.weight > 0) base = PredictA(near, de);
      da = decode_difference(near.weight > 0 ? models->a_near : models->a);
    } else {
      da = decode_difference(models->a);
      if (bits) de = decode_difference(models->b[bits]);
    }
    const int a[3] = {base[0] + da[0], base[1] + da[1], base[2] + da[2]};
    const int e[3] = {a[0] + de[0], a[1] + de[1], a[2] + de[2]};
    for (int ch = 0; ch < 3; ++ch) {
      if (a[ch] < 0 || a[ch] > 255 || e[ch] < 0 || e[ch] > 255) return Corrupt("color block endpoint outside 0..255");
    }
    Endpoints ends{{uint8_t(a[0]), uint8_t(a[1]), uint8_t(a[2])}, {uint8_t(e[0]), uint8_t(e[1]), uint8_t(e[2])}};
    d.starts_.push_back(static_cast<uint32_t>(next));
    d.weight_offsets_.push_back(weight_bits);
    d.bits_.push_back(static_cast<uint8_t>(bits));
    d.ends_.push_back(ends);
    uint32_t prev_w = 16;
    // The colors of the block's weights, each interpolated at its first use (Interpolate divides by a
    // width known only here): lion 1 cm at 38 dB 8.7 -> 0.04 M instructions.
    std::array<Rgb8, 1 << kMaxWeightBits> palette;
    uint32_t interpolated = 0;  // a bit per weight
    if (bits) d.weights_.resize((weight_bits + uint64_t{length} * static_cast<uint64_t>(bits) + 63) / 64 + 1, 0);
    if (grouped && bits) {
      if (!DecodeWeightGroups(groups, codes->tables[bits].data(), bits, length, d.weights_.data(), weight_bits)) {
        return Corrupt("color weight group is no code, or sets bits past its block");
      }
      weight_bits += uint64_t{length} * static_cast<uint64_t>(bits);
    } else if (!mixed && !spatial && bits) {
      const std::span<BitTreeModel<kMaxWeightBits>> plain(models->weight[bits]);
      switch (bits) {
        case 1: DecodePlainWeights<1>(rc, plain, length, d.weights_.data(), weight_bits); break;
        case 2: DecodePlainWeights<2>(rc, plain, length, d.weights_.data(), weight_bits); break;
        case 3: DecodePlainWeights<3>(rc, plain, length, d.weights_.data(), weight_bits); break;
        default: DecodePlainWeights<4>(rc, plain, length, d.weights_.data(), weight_bits); break;
      }
      weight_bits += uint64_t{length} * static_cast<uint64_t>(bits);
    }
    for (uint32_t i = 0; (mixed || spatial) && bits && i < length; ++i) {
      uint32_t w;
      if (mixed) {
        w = mixer->Decode(rc, bits, {spatial->Position(next + i, ends, bits, true), prev_w});
      } else {
        const uint32_t context = spatial ? spatial->Of(next + i, ends, bits, prev_w) : prev_w;
        w = DecodeBitTree<kMaxWeightBits>(rc, models->weight[bits][context], bits);
      }
      d.weights_[weight_bits >> 6] |= uint64_t{w} << (weight_bits & 63);
      if ((weight_bits & 63) + static_cast<uint64_t>(bits) > 64) d.weights_[(weight_bits >> 6) + 1] |= uint64_t{w} >> (64 - (weight_bits & 63));
      weight_bits += static_cast<uint64_t>(bits);
      if (!(interpolated >> w & 1)) {
        palette[w] = Interpolate(ends, w, bits);
        interpolated |= 1u << w;
      }
      if (spatial) spatial->Record(next + i, palette[w]);
      prev_w = w;
    }
    for (uint32_t i = 0; spatial && !bits && i < length; ++i) spatial->Record(next + i, ends.a);
    if (rc.overrun() || groups.overrun()) return Truncated("color stream is cut short");
    next += length;
    prev_bits = bits;
    prev_a = ends.a;
  }
  if (next != count) return Corrupt("color blocks do not cover every color");
  d.weights_.resize((weight_bits + 63) / 64 + 1);
  // Macro-block table: the first block of every macro block.
  const uint64_t macros = (d.count_ + kMacroBlockColors - 1) / kMacroBlockColors;
  for (uint64_t m = 0, k = 0; m <= macros; ++m) {
    while (k < d.starts_.size() && d.starts_[k] < m * kMacroBlockColors) ++k;
    d.macro_first_block_.push_back(static_cast<uint32_t>(k));
  }
  return d;
}

uint32_t BlockColorDecoder::Weight(uint64_t bit_offset, int bits) const { return PackedWeight(weights_.data(), bit_offset, bits); }

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
  // Block by block: the width is dispatched once per block, not once per color.
  for (uint64_t i = begin; i < end; ++block) {
    const uint64_t stop = block + 1 < starts_.size() ? std::min<uint64_t>(end, starts_[block + 1]) : end;
    const uint64_t n = stop - i;
    const uint64_t offset = weight_offsets_[block] + (i - starts_[block]) * bits_[block];
    switch (bits_[block]) {
      case 1: DecodeRun<1>(ends_[block], weights_.data(), offset, n, out); break;
      case 2: DecodeRun<2>(ends_[block], weights_.data(), offset, n, out); break;
      case 3: DecodeRun<3>(ends_[block], weights_.data(), offset, n, out); break;
      case 4: DecodeRun<4>(ends_[block], weights_.data(), offset, n, out); break;
      default: std::fill(out, out + n, ends_[block].a); break;
    }
    out += n;
    i = stop;
  }
}

std::vector<Rgb8> BlockColorDecoder::DecodeAll() const {
  std::vector<Rgb8> colors(count_);
  Decode(0, count_, colors.data());
  return colors;
}

std::vector<uint8_t> BlockColorDecoder::BlockWeights(size_t block) const {
  const uint64_t end = block + 1 < starts_.size() ? starts_[block + 1] : count_;
  std::vector<uint8_t> weights(bits_[block] ? end - starts_[block] : 0);
  for (size_t i = 0; i < weights.size(); ++i) weights[i] = static_cast<uint8_t>(Weight(weight_offsets_[block] + i * bits_[block], bits_[block]));
  return weights;
}

size_t BlockColorDecoder::ResidentBytes() const {
  return starts_.size() * (4 + 8 + 1 + sizeof(Endpoints)) + macro_first_block_.size() * 4 + weights_.size() * 8;
}

}  // namespace pointdag
