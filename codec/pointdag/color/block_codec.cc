#include "pointdag/color/block_codec.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cstring>
#include <memory>
#include <optional>
#include <string>

#include "pointdag/color/block_stream.h"
#include "pointdag/color/fixed_weight_codes.h"
#include "pointdag/color/prefix_weights.h"
#include "pointdag/color/weight_choice.h"
#include "pointdag/color/weight_mixer.h"
#include "pointdag/entropy/varint.h"
#include "pointdag/gpu/color_blocks.h"
#include "pointdag/gpu/stage_device.h"

namespace pointdag {
namespace {

// A candidate's fit is computed where a merge is tried or the cut weighs it, once.
struct Candidate {
  uint32_t start, length;  // within the macro block
  std::optional<BlockFit> fit;
  std::optional<uint64_t> chroma = std::nullopt;  // its error's chroma part, where the variable-rate tree weighs it
  uint32_t failed_with = 0;  // length of the right neighbour a merge with failed (it would fail again)
};

const BlockFit& FitOf(const BlockFitter& fitter, Candidate& c, int bits) {
  if (!c.fit) c.fit = fitter.Fit(c.start, c.length, bits);
  return *c.fit;
}

// What the variable-rate tree and cut weigh a block's error by: BlockError (luma 6:1:1 over chroma,
// as the fitter) plus kChromaTimes x its chroma part, 1024 x 1/2 (cb cb^T + cr cr^T) rounded, of the
// block rebuilt with projected weights: 6:5:5 in all. With BlockError alone the cut merged blocks of
// different hue where it saved bits: lion and the milk carton lost 0.8-2.2 dB of RGB PSNR at equal
// PSNR-Y; 6:5:5 gives most of it back for 2-9 % more bits (6:9:9 put autzen at 42 dB above RAHT).
// As gpu/shaders/block_common.glsl (WeighedError).
constexpr uint64_t kChromaTimes = 4;

// The chroma part of candidate c fitted as `fit`: the fit's own where it has it, else a walk that
// may stop once it passes `give_up_above`.
uint64_t ChromaOf(const BlockFitter& fitter, const Candidate& c, const BlockFit& fit, int bits, uint64_t give_up_above = UINT64_MAX) {
  return fit.chroma != kUnknownChroma ? fit.chroma : fitter.ChromaError(c.start, c.length, bits, fit.ends, give_up_above);
}

uint64_t WeighedError(const BlockFitter& fitter, Candidate& c, int bits) {
  const BlockFit& fit = FitOf(fitter, c, bits);
  if (!c.chroma) c.chroma = ChromaOf(fitter, c, fit, bits);
  return fit.sse + kChromaTimes * *c.chroma;
}

// Fixed rate: a block passes when its mean error per channel, sse / (3 length) with sse the
// BlockError sum in 1/1024ths, is within the threshold. Variable rate: the same number prices a
// bit (VariableRateMacroBlock). In integers (so that the Vulkan port decides alike):
// scaled = floor(3072 max_mse).
struct Threshold {
  uint64_t scaled;
  explicit Threshold(double max_mse) : scaled(static_cast<uint64_t>(std::clamp(max_mse * 3072.0, 0.0, 1073741824.0))) {}
  uint64_t MaxSse(uint32_t length) const { return length * scaled; }
};

// Paper IIA's merge passes, from the given blocks, at `bits` per weight: each pass walks the blocks
// and merges a block with its right neighbour where the merged block's error is within
// limit(block, neighbour); a block merges at most once per pass; passes repeat until one merges
// nothing. A pair that failed is not fitted again while both blocks stay as they are. (Trying the
// left neighbour as well, as IIA does, never changes anything here: a block's left neighbour is
// unmerged only when their merge has just failed.) Where `weighed` (variable rate), the merged
// block's WeighedError must be within the limit as well.
template <typename Limit>
std::vector<Candidate> MergePasses(const BlockFitter& fitter, std::vector<Candidate> blocks, int bits, Limit limit_of,
                                   bool weighed = false) {
  for (bool merged_any = true; merged_any;) {
    merged_any = false;
    std::vector<Candidate> out;
    out.reserve(blocks.size());
    for (size_t i = 0; i < blocks.size(); ++i) {
      if (i + 1 < blocks.size() && blocks[i].failed_with != blocks[i + 1].length) {
        const uint32_t length = blocks[i].length + blocks[i + 1].length;
        const uint64_t limit = limit_of(blocks[i], blocks[i + 1]);
        const BlockFit fit = fitter.Fit(blocks[i].start, length, bits, limit);
        if (fit.sse <= limit) {
          Candidate merged{blocks[i].start, length, fit};
          // Most weighed trials that fail here do so on their chroma part: its walk stops once it passes what is left.
          const uint64_t chroma_limit = (limit - fit.sse) / kChromaTimes;
          if (weighed) merged.chroma = ChromaOf(fitter, merged, fit, bits, chroma_limit);
          if (!weighed || *merged.chroma <= chroma_limit) {
            out.push_back(std::move(merged));
            merged_any = true;
            ++i;
            continue;
          }
        }
        blocks[i].failed_with = blocks[i + 1].length;
      }
      out.push_back(blocks[i]);
    }
    blocks.swap(out);
  }
  return blocks;
}

std::vector<Candidate> Singletons(uint32_t count) {
  std::vector<Candidate> blocks;
  blocks.reserve(count);
  for (uint32_t i = 0; i < count; ++i) blocks.push_back({i, 1, std::nullopt});
  return blocks;
}

// The bits the variable-rate tree and cut weigh a block by, in tenths of a bit: a weight of 1..4
// bits what block stream version 4 spends on it (0.6 / 1.0 / 1.7 / 2.5 bits), the header (length,
// width, endpoint A) 100 bits and endpoint B 100, where the stream spends ~23 and ~20: a block
// boundary also costs the weights after it their context and the threshold search more units to
// correct. The stream's own costs made lion, guanyin and autzen 3-10 % larger at equal PSNR-Y,
// headers of 30 and 30 bits with the weights at 0.7 of these 1-4 % (docs/benchmarks.md). A bit is
// worth half the threshold, half the weight choice's price (weight_choice.h): a block costs
// kTenthsPerSse x its error + scaled x its tenths of a bit (lambdas of 1 and 2 x this: 1 % larger).
constexpr uint64_t kHeaderTenths = 1000, kSecondEndTenths = 1000;
constexpr std::array<uint64_t, kMaxWeightBits + 1> kWeightTenths = {0, 6, 10, 17, 25};
constexpr uint64_t kTenthsPerSse = 20;
uint64_t RateTenths(uint32_t length, int bits) {
  return kHeaderTenths + (bits ? kSecondEndTenths : 0) + uint64_t{length} * kWeightTenths[bits];
}

// The first level of the tree above the leaves that merges blocks; the levels below it keep the
// leaves (refitted). Merging at 1 bit as well measured the same or larger at equal PSNR-Y (lion,
// guanyin, autzen), for 1/6 more fitted colors. As gpu/pointdag/gpu/color_blocks.cc.
constexpr int kFirstMergedBits = 2;

// Paper IIB's block tree of one macro block (levels 0..4 bits) and its cut, by rate and distortion
// together: a merge is kept where it adds less error than the header it saves is worth, and the cut
// keeps a block where its error plus its bits, both in BlockError units, cost less than its
// children's (ties: the children, fewer bits each). Lion, guanyin, autzen 3-12 % smaller at equal
// PSNR-Y than a tree whose every block met the threshold, cut by bits alone (docs/benchmarks.md).
std::vector<ColorBlock> VariableRateMacroBlock(const BlockFitter& fitter, uint32_t count, Threshold threshold) {
  std::vector<std::vector<Candidate>> levels;
  for (int bits = 0; bits <= kMaxWeightBits; ++bits) {
    std::vector<Candidate> start;  // the leaves, or the previous level's blocks to be refitted with more bits
    if (bits == 0) {
      start = Singletons(count);
    } else {
      start.reserve(levels.back().size());
      for (const Candidate& c : levels.back()) start.push_back({c.start, c.length, std::nullopt});
    }
    if (bits > 0 && bits < kFirstMergedBits) {
      levels.push_back(std::move(start));
      continue;
    }
    const uint64_t saved = threshold.scaled * (kHeaderTenths + (bits ? kSecondEndTenths : 0)) / kTenthsPerSse;
    levels.push_back(MergePasses(fitter, std::move(start), bits, [&](Candidate& a, Candidate& b) {
      return WeighedError(fitter, a, bits) + WeighedError(fitter, b, bits) + saved;
    }, true));
  }
  // Cut bottom-up: best[level][k] is the cheapest way to code block k of that level.
  struct Best {
    uint64_t cost;
    bool keep_self;
  };
  std::vector<std::vector<Best>> best(levels.size());
  for (size_t level = 0; level < levels.size(); ++level) {
    size_t child = 0;
    for (Candidate& c : levels[level]) {
      uint64_t children = UINT64_MAX;
      if (level > 0) {
        children = 0;
        for (; child < levels[level - 1].size() && levels[level - 1][child].start < c.start + c.length; ++child) {
          children += best[level - 1][child].cost;
        }
      }
      const int bits = static_cast<int>(level);
      // A block whose bits alone cost what its children do loses whatever its error: not fitted (most
      // 1-bit refits, which nothing but the cut weighs).
      const uint64_t rate = threshold.scaled * RateTenths(c.length, bits);
      if (rate >= children) {
        best[level].push_back(Best{children, false});
        continue;
      }
      const uint64_t own = kTenthsPerSse * WeighedError(fitter, c, bits) + rate;
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
        out.push_back({it->start, it->length, static_cast<uint8_t>(level), it->fit->ends});
      } else {
        self(self, level - 1, it->start, it->start + it->length);
      }
    }
  };
  expand(expand, levels.size() - 1, 0, count);
  return out;
}


std::vector<ColorBlock> EncodeBlocksOnCpu(std::span<const Rgb8> colors, BlockLayout layout, Threshold threshold) {
  // Macro blocks are independent: encode them in parallel, concatenate in order.
  const size_t macros = (colors.size() + kMacroBlockColors - 1) / kMacroBlockColors;
  std::vector<std::vector<ColorBlock>> per_macro(macros);
  tbb::parallel_for(size_t{0}, macros, [&](size_t m) {
    const uint32_t begin = static_cast<uint32_t>(m * kMacroBlockColors);
    const uint32_t count = static_cast<uint32_t>(std::min<size_t>(colors.size() - begin, kMacroBlockColors));
    const BlockFitter fitter(colors.subspan(begin, count));
    if (layout == BlockLayout::kVariableRate) {
      per_macro[m] = VariableRateMacroBlock(fitter, count, threshold);
    } else {
      const auto limit = [&](const Candidate& a, const Candidate& b) { return threshold.MaxSse(a.length + b.length); };
      for (Candidate& c : MergePasses(fitter, Singletons(count), kFixedRateBits, limit)) {
        per_macro[m].push_back({c.start, c.length, kFixedRateBits, FitOf(fitter, c, kFixedRateBits).ends});
      }
    }
    for (ColorBlock& b : per_macro[m]) b.start += begin;
  });
  std::vector<ColorBlock> blocks;
  for (const auto& macro : per_macro) blocks.insert(blocks.end(), macro.begin(), macro.end());
  return blocks;
}

// The same blocks from the Vulkan kernels (gpu/shaders/block_*.comp).
StatusOr<std::vector<ColorBlock>> EncodeBlocksOnDevice(gpu::VulkanContext& device, std::span<const Rgb8> colors,
                                                       BlockLayout layout, Threshold threshold) {
  static_assert(sizeof(Rgb8) == 3);
  const std::span<const uint8_t> rgb(reinterpret_cast<const uint8_t*>(colors.data()), colors.size() * 3);
  ASSIGN_OR_RETURN(const auto on_device, gpu::EncodeColorBlocks(device, rgb, layout == BlockLayout::kFixedRate, threshold.scaled));
  std::vector<ColorBlock> blocks;
  blocks.reserve(on_device.size());
  for (const gpu::DeviceColorBlock& b : on_device) {
    blocks.push_back({b.start, b.length, b.bits, {{b.a[0], b.a[1], b.a[2]}, {b.b[0], b.b[1], b.b[2]}}});
  }
  return blocks;
}

// Both paths on 4 macro blocks of a noisy gradient (the Vulkan one after a warm-up run).
constexpr size_t kCalibrationColors = 4 * kMacroBlockColors;
StatusOr<gpu::StageTiming> CalibrateColorBlocks(gpu::VulkanContext& device) {
  std::vector<Rgb8> colors(kCalibrationColors);
  uint32_t noise = 12345;
  for (size_t i = 0; i < colors.size(); ++i) {
    noise = noise * 1664525u + 1013904223u;
    const auto channel = [&](double base, int shift) { return static_cast<uint8_t>(std::clamp(base + ((noise >> shift) & 7), 0.0, 255.0)); };
    const double t = static_cast<double>(i % 4096) / 4096.0;
    colors[i] = {channel(40 + 180 * t, 8), channel(200 - 150 * t, 16), channel(90 + 60 * t, 24)};
  }
  const Threshold threshold(16.0);
  return tbb::this_task_arena::isolate([&]() -> StatusOr<gpu::StageTiming> {
    using Clock = std::chrono::steady_clock;
    const auto seconds = [](Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); };
    gpu::StageTiming timing;
    auto start = Clock::now();
    EncodeBlocksOnCpu(colors, BlockLayout::kVariableRate, threshold);
    timing.cpu_seconds = seconds(start);
    RETURN_IF_ERROR(EncodeBlocksOnDevice(device, colors, BlockLayout::kVariableRate, threshold).status());
    start = Clock::now();
    RETURN_IF_ERROR(EncodeBlocksOnDevice(device, colors, BlockLayout::kVariableRate, threshold).status());
    timing.vulkan_seconds = seconds(start);
    return timing;
  });
}

}  // namespace

StatusOr<gpu::VulkanContext*> ColorBlocksDevice() { return gpu::DeviceFor(gpu::Stage::kColorBlocks, CalibrateColorBlocks); }

StatusOr<std::vector<ColorBlock>> EncodeBlocks(std::span<const Rgb8> colors, BlockLayout layout, double max_mse) {
  const Threshold threshold(max_mse);
  ASSIGN_OR_RETURN(gpu::VulkanContext* const device,
                   gpu::DeviceFor(gpu::Stage::kColorBlocks, CalibrateColorBlocks, colors.size() < kCalibrationColors));
  if (device) return EncodeBlocksOnDevice(*device, colors, layout, threshold);
  return EncodeBlocksOnCpu(colors, layout, threshold);
}

StatusOr<std::vector<uint8_t>> SerializeBlocks(std::span<const Rgb8> colors, std::span<const ColorBlock> blocks,
                                               BlockLayout layout, std::span<const uint64_t> morton,
                                               std::vector<Rgb8>* decoded, std::span<const uint8_t> weights) {
  return SerializeBlocksAsVersion(colors, blocks, layout, morton.empty() ? kPlainVersion : kMixedVersion, morton, decoded, weights);
}

StatusOr<std::vector<uint8_t>> SerializeBlocksAsVersion(std::span<const Rgb8> colors, std::span<const ColorBlock> blocks,
                                                        BlockLayout layout, uint8_t version, std::span<const uint64_t> morton,
                                                        std::vector<Rgb8>* decoded, std::span<const uint8_t> chosen) {
  if (!IsBlockStreamVersion(version)) return InvalidArgument("color stream version " + std::to_string(version) + " is unknown");
  if (HasSpatialContexts(version) && morton.size() != colors.size()) {
    return InvalidArgument("color stream version " + std::to_string(version) + " needs one Morton code per color");
  }
  if (!chosen.empty() && chosen.size() != colors.size()) return InvalidArgument("chosen weights must be one per color");
  const DifferenceCode code{version >= 2};
  const bool mixed = version == kMixedVersion;
  const bool grouped = version == kFixedWeightCodesVersion;
  std::optional<WeightContexts> spatial;
  if (HasSpatialContexts(version)) spatial.emplace(morton);
  std::vector<uint8_t> out = {version, static_cast<uint8_t>(layout), 0, 0};
  PutVarint(out, colors.size());
  PutVarint(out, blocks.size());
  // Default-initialized (new T, not make_unique's new T(); emscripten's libc++ lacks
  // make_unique_for_overwrite): every model starts at its own initializer; make_unique would zero the
  // 41 KB first (a memset that was 5 % of a small tile's decode).
  std::unique_ptr<BlockModels> models(new BlockModels);
  std::optional<WeightMixer> mixer;
  if (mixed) mixer.emplace();
  BinaryRangeEncoder rc;
  BitWriter groups;  // version 6: the weights' groups, after the range-coded section
  std::vector<uint8_t> block_groups;
  uint64_t next = 0;
  int prev_bits = 0;
  Rgb8 prev_a{};
  std::vector<uint8_t> weights(kMacroBlockColors);
  if (decoded) decoded->resize(colors.size());
  const auto encode_difference = [&](std::array<GammaModel, 3>& m, int dr, int dg, int db) {
    const auto d = code.Components(dr, dg, db);
    for (int c = 0; c < 3; ++c) EncodeGamma(rc, m[c], ZigZag(d[c]), code.MaxBits());
  };
  for (const ColorBlock& b : blocks) {
    if (b.start != next || b.length == 0 || b.length > kMacroBlockColors || b.bits > kMaxWeightBits ||
        b.start + b.length > colors.size()) {
      return Internal("color blocks do not tile the colors");
    }
    next += b.length;
    EncodeGamma(rc, models->length[prev_bits], b.length, kLengthBits);
    if (layout == BlockLayout::kVariableRate) EncodeBitTree<3>(rc, models->width[prev_bits], b.bits);
    const Endpoints& e = b.ends;
    const std::array<int, 3> span = {e.b.r - e.a.r, e.b.g - e.a.g, e.b.b - e.a.b};
    if (mixed) {
      // B - A first: the prediction of A aims the segment's middle at the neighbours' mean.
      if (b.bits) encode_difference(models->b[b.bits], span[0], span[1], span[2]);
      const BlockSurroundings near = spatial->Surroundings(b.start, b.length);
      if (near.weight > 0) {
        const auto p = PredictA(near, b.bits ? span : std::array<int, 3>{});
        encode_difference(models->a_near, e.a.r - p[0], e.a.g - p[1], e.a.b - p[2]);
      } else {
        encode_difference(models->a, e.a.r - prev_a.r, e.a.g - prev_a.g, e.a.b - prev_a.b);
      }
    } else {
      encode_difference(models->a, e.a.r - prev_a.r, e.a.g - prev_a.g, e.a.b - prev_a.b);
      if (b.bits) encode_difference(models->b[b.bits], span[0], span[1], span[2]);
    }
    if (b.bits) {
      std::span<const uint8_t> block_weights = weights;
      if (chosen.empty()) {
        ChooseBlockWeights(colors, b, weights);
      } else {
        block_weights = chosen.subspan(b.start, b.length);
      }
      std::array<Rgb8, 1 << kMaxWeightBits> palette;  // Interpolate divides by a run-time 2^bits - 1: once per weight value
      for (uint32_t w = 0; w < (1u << b.bits); ++w) palette[w] = Interpolate(b.ends, w, b.bits);
      if (grouped) {
        block_groups.clear();
        AppendWeightGroups(block_weights.first(b.length), b.bits, block_groups);
        const std::vector<PrefixEncoder>& codes = FixedWeightGroupCodes().encoders[b.bits];
        const int per = WeightsPerGroup(b.bits);
        for (size_t g = 0; g < block_groups.size(); ++g) {
          codes[g ? block_weights[g * per - 1] : 1 << b.bits].Put(groups, block_groups[g]);
        }
      }
      uint32_t prev_w = 16;
      for (uint32_t i = b.start; i < b.start + b.length; ++i) {
        const uint32_t w = block_weights[i - b.start];
        if (mixed) {
          mixer->Encode(rc, b.bits, {spatial->Position(i, b.ends, b.bits, true), prev_w}, w);
        } else if (!grouped) {
          const uint32_t context = spatial ? spatial->Of(i, b.ends, b.bits, prev_w) : prev_w;
          EncodeBitTree<kMaxWeightBits>(rc, models->weight[b.bits][context], w, b.bits);
        }
        const Rgb8 c = palette[w];
        if (spatial) spatial->Record(i, c);
        if (decoded) (*decoded)[i] = c;
        prev_w = w;
      }
    } else {
      for (uint32_t i = b.start; spatial && i < b.start + b.length; ++i) spatial->Record(i, b.ends.a);
      if (decoded) std::fill_n(decoded->begin() + b.start, b.length, b.ends.a);
    }
    prev_bits = b.bits;
    prev_a = b.ends.a;
  }
  if (next != colors.size()) return Internal("color blocks do not cover the colors");
  std::vector<uint8_t> payload = rc.Finish();
  if (grouped) {  // the range-coded section's length, the section, then the groups
    std::vector<uint8_t> sections;
    PutVarint(sections, payload.size());
    sections.insert(sections.end(), payload.begin(), payload.end());
    const std::vector<uint8_t> group_bytes = groups.Finish();
    sections.insert(sections.end(), group_bytes.begin(), group_bytes.end());
    payload = std::move(sections);
  }
  PutVarint(out, payload.size());  // a range decoder may not miss its last bytes: cuts must show
  out.insert(out.end(), payload.begin(), payload.end());
  return out;
}

}  // namespace pointdag
