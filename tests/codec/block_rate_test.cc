// The encoder's rate-aware weight choice (color/weight_choice.h): the decoder rebuilds what the
// choice picked, price 0 keeps the error-minimizing weights, and a price saves weight bits.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "pointdag/color/block_codec.h"
#include "pointdag/color/block_target.h"
#include "pointdag/color/color_metrics.h"
#include "pointdag/color/weight_choice.h"

namespace pointdag {
namespace {

// A noisy gradient: weights of neighbours differ by noise, which a price can smooth away.
std::vector<Rgb8> NoisyGradient(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 4.0);
  std::vector<Rgb8> colors(n);
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i % 700) / 700.0;
    const auto ch = [&](double base) { return static_cast<uint8_t>(std::clamp(std::lround(base + noise(rng)), 0l, 255l)); };
    colors[i] = {ch(30 + 190 * t), ch(60 + 120 * t), ch(200 - 150 * t)};
  }
  return colors;
}

std::vector<uint8_t> Weights(std::span<const Rgb8> colors, const ColorBlock& b) {
  std::vector<uint8_t> w(b.length);
  ChooseBlockWeights(colors, b, w);
  return w;
}

std::vector<Rgb8> Rebuilt(std::span<const Rgb8> colors, std::span<const ColorBlock> blocks) {
  std::vector<Rgb8> out(colors.size());
  for (const ColorBlock& b : blocks) {
    const auto w = Weights(colors, b);
    for (uint32_t i = 0; i < b.length; ++i) out[b.start + i] = Interpolate(b.ends, w[i], b.bits);
  }
  return out;
}

std::vector<ColorBlock> WithPrice(std::vector<ColorBlock> blocks, uint32_t price) {
  for (ColorBlock& b : blocks) b.rate_price = price;
  return blocks;
}

TEST(WeightChoice, PriceZeroKeepsTheErrorMinimizingWeights) {
  const auto colors = NoisyGradient(3000, 1);
  for (int bits = 1; bits <= kMaxWeightBits; ++bits) {
    const ColorBlock b{100, 2000, static_cast<uint8_t>(bits), BlockFitter(colors).Fit(100, 2000, bits).ends, 0};
    const auto w = Weights(colors, b);
    for (uint32_t i = 0; i < b.length; ++i) ASSERT_EQ(w[i], ChooseWeight(colors[b.start + i], b.ends, bits)) << i;
  }
}

TEST(WeightChoice, AHigherPriceSavesBitsForError) {
  const auto colors = NoisyGradient(40000, 2);
  const auto blocks = *EncodeBlocks(colors, BlockLayout::kVariableRate, 12.0);
  size_t last_size = SIZE_MAX;
  double last_error = -1;
  for (uint32_t price : {0u, WeightRatePrice(12.0, colors.size()), 4 * WeightRatePrice(12.0, colors.size())}) {
    const auto priced = WithPrice(blocks, price);
    const auto stream = *SerializeBlocks(colors, priced, BlockLayout::kVariableRate);
    auto decoder = BlockColorDecoder::Open(stream, colors.size());
    ASSERT_TRUE(decoder.ok()) << decoder.status().ToString();
    const auto decoded = decoder->DecodeAll();
    ASSERT_EQ(decoded, Rebuilt(colors, priced)) << price;  // the decoder rebuilds the choice
    for (uint32_t i = 0; i < colors.size(); i += 997) ASSERT_EQ(decoder->At(i), decoded[i]);
    double error = 0;
    for (size_t i = 0; i < colors.size(); ++i) error += BlockError(colors[i], decoded[i]);
    EXPECT_LT(stream.size(), last_size) << price;
    EXPECT_GT(error, last_error) << price;
    last_size = stream.size();
    last_error = error;
  }
}

// Refitted endpoints are kept only where they lower the priced cost, and they often do.
TEST(WeightChoice, RefitNeverRaisesTheCost) {
  const auto colors = NoisyGradient(40000, 4);
  const auto blocks = WithPrice(*EncodeBlocks(colors, BlockLayout::kVariableRate, 12.0), WeightRatePrice(12.0, colors.size()));
  std::vector<uint8_t> w(kMacroBlockColors), refit(kMacroBlockColors);
  size_t moved = 0;
  for (ColorBlock b : blocks) {
    const uint64_t before = ChooseBlockWeights(colors, b, w);
    const Endpoints ends = b.ends;
    RefitEnds(colors, b, refit);
    EXPECT_LE(ChooseBlockWeights(colors, b, w), before);
    // The weights it leaves are those of the block it leaves.
    EXPECT_TRUE(std::equal(w.begin(), w.begin() + b.length, refit.begin()));
    moved += !(b.ends == ends);
  }
  EXPECT_GT(moved, 0u);
}

// Small arrays are not priced (their weight models stay young).
TEST(WeightChoice, PricedFromAMacroBlockOfColors) {
  EXPECT_EQ(WeightRatePrice(12.0, kMacroBlockColors - 1), 0u);
  EXPECT_GT(WeightRatePrice(12.0, kMacroBlockColors), 0u);
  EXPECT_EQ(WeightRatePrice(0.0, kMacroBlockColors), 0u);
}

// The threshold search measures the priced reconstruction, so the stored colors meet the target.
TEST(WeightChoice, TargetsAreMetWithPricedWeights) {
  const auto colors = NoisyGradient(3 * kMacroBlockColors + 123, 3);
  for (double target : {32.0, 38.0, 44.0}) {
    auto found = BlocksForTarget(colors, {}, BlockLayout::kVariableRate, target);
    ASSERT_TRUE(found.ok()) << found.status().ToString();
    bool priced = false;
    for (const ColorBlock& b : found->blocks) priced |= b.rate_price > 0;
    EXPECT_TRUE(priced) << target;
    const auto decoded = BlockColorDecoder::Open(*SerializeBlocks(colors, found->blocks, BlockLayout::kVariableRate), colors.size())->DecodeAll();
    const double psnr = MeasureColorPsnr(colors, decoded).y;
    EXPECT_GE(psnr, target);
    EXPECT_LT(psnr, target + 0.5);
  }
}

// BlocksForTarget hands over the weights it measured its blocks with; they are the ones the writer
// would choose: the stream is the same byte for byte, with and without spatial contexts.
TEST(WeightChoice, TargetBlocksCarryTheWrittenWeights) {
  const auto colors = NoisyGradient(3 * kMacroBlockColors + 123, 5);
  std::vector<uint64_t> morton(colors.size());
  for (size_t i = 0; i < morton.size(); ++i) morton[i] = 3 * i;
  for (const BlockLayout layout : {BlockLayout::kVariableRate, BlockLayout::kFixedRate}) {
    const auto found = BlocksForTarget(colors, {}, layout, 38.0);
    ASSERT_TRUE(found.ok());
    ASSERT_EQ(found->weights.size(), colors.size());
    for (const std::span<const uint64_t> codes : {std::span<const uint64_t>(), std::span<const uint64_t>(morton)}) {
      const auto chosen = SerializeBlocks(colors, found->blocks, layout, codes, nullptr, found->weights);
      const auto again = SerializeBlocks(colors, found->blocks, layout, codes);
      ASSERT_TRUE(chosen.ok() && again.ok());
      EXPECT_EQ(*chosen, *again);
    }
  }
  EXPECT_FALSE(SerializeBlocks(colors, {}, BlockLayout::kVariableRate, {}, nullptr, std::vector<uint8_t>(7)).ok());
}

}  // namespace
}  // namespace pointdag
