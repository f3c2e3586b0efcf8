// Block color stream version 6 (tiles): weights in groups read by table lookup in codes fixed by
// the format (color/prefix_weights.h, color/fixed_weight_codes.h, proto/PDAG_FORMAT.md §3).
#include <gtest/gtest.h>
#include <openssl/sha.h>

#include <filesystem>
#include <random>
#include <string>

#include "pointdag/color/block_codec.h"
#include "pointdag/color/block_stream.h"
#include "pointdag/color/fixed_weight_codes.h"
#include "pointdag/color/prefix_weights.h"
#include "test_util.h"

namespace pointdag {
namespace {

std::string SourceText(const char* relative) {
  const std::vector<uint8_t> bytes = testing::ReadBytes(std::filesystem::path(POINTDAG_SOURCE_DIR) / relative);
  return {bytes.begin(), bytes.end()};
}

std::string Sha256Hex(const std::string& text) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(text.data()), text.size(), digest);
  std::string hex;
  for (unsigned char c : digest) hex += "0123456789abcdef"[c >> 4], hex += "0123456789abcdef"[c & 15];
  return hex;
}

// The compiled-in codes are the normative file byte for byte, and the file is the one whose
// SHA-256 the spec gives (web/src/decoder/fixed_weight_codes.js is checked by tests/web).
TEST(FixedWeightCodes, AreTheNormativeTable) {
  const std::string table = SourceText("proto/tables/block_weight_codes_v6.txt");
  EXPECT_EQ(FixedWeightCodesText(), table) << "regenerate: weight_codes_trainer emit (tools/weight_codes_trainer.cc)";
  EXPECT_EQ(table.size(), 6976u + 34u);
  const std::string spec = SourceText("proto/PDAG_FORMAT.md");
  EXPECT_NE(spec.find("block_weight_codes_v6.txt` of this repository (7,010\n  bytes, SHA-256 `" + Sha256Hex(table) + "`"), std::string::npos)
      << "the spec's SHA-256 of the table is not " << Sha256Hex(table);
  // Every symbol of every code has a length of 1..12 and every code is complete.
  const FixedWeightCodes& codes = FixedWeightGroupCodes();
  for (int bits = 1; bits <= 4; ++bits) {
    ASSERT_EQ(codes.encoders[bits].size(), static_cast<size_t>(GroupContexts(bits)));
    for (int c = 0; c < GroupContexts(bits); ++c) {
      uint64_t kraft = 0;
      for (int s = 0; s < 256; ++s) {
        const int length = codes.lengths[bits][c][s];
        EXPECT_EQ(length > 0, s < GroupSymbols(bits)) << bits << " " << c << " " << s;
        if (length) kraft += uint64_t{1} << (kPrefixCodeBits - length);
      }
      EXPECT_EQ(kraft, uint64_t{1} << kPrefixCodeBits) << "width " << bits << " context " << c;
    }
  }
}

std::vector<Rgb8> NoisyGradient(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Rgb8> colors(n);
  for (size_t i = 0; i < n; ++i) {
    const int v = static_cast<int>((i * 7) % 200) + static_cast<int>(rng() % 40);
    colors[i] = {static_cast<uint8_t>(v), static_cast<uint8_t>(255 - v), static_cast<uint8_t>((v * 3) % 256)};
  }
  return colors;
}

// Version 6 decodes to what version 2 decodes (same blocks, weights coded otherwise), in both
// layouts and at several rates (blocks of every width and of lengths that end inside a group).
TEST(FixedWeightCodes, Version6DecodesAsVersion2) {
  const std::vector<Rgb8> colors = NoisyGradient(40000, 3);
  for (BlockLayout layout : {BlockLayout::kVariableRate, BlockLayout::kFixedRate}) {
    for (double max_mse : {0.0, 4.0, 30.0, 200.0}) {
      const auto blocks = *EncodeBlocks(colors, layout, max_mse);
      std::vector<Rgb8> rebuilt;
      const auto v6 = SerializeBlocksAsVersion(colors, blocks, layout, kFixedWeightCodesVersion, {}, &rebuilt);
      ASSERT_TRUE(v6.ok()) << v6.status().ToString();
      EXPECT_EQ((*v6)[0], 6);
      const auto v2 = *SerializeBlocksAsVersion(colors, blocks, layout, 2);
      const auto decoded = BlockColorDecoder::Open(*v6, colors.size());
      ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
      EXPECT_EQ(decoded->DecodeAll(), BlockColorDecoder::Open(v2, colors.size())->DecodeAll()) << max_mse;
      EXPECT_EQ(decoded->DecodeAll(), rebuilt);
    }
  }
}

// Version 5 was never released: neither written nor read.
TEST(FixedWeightCodes, Version5IsRefused) {
  const std::vector<Rgb8> colors = NoisyGradient(500, 1);
  const auto blocks = *EncodeBlocks(colors, BlockLayout::kVariableRate, 10.0);
  EXPECT_EQ(SerializeBlocksAsVersion(colors, blocks, BlockLayout::kVariableRate, 5).status().code(), StatusCode::kInvalidArgument);
  auto stream = *SerializeBlocksAsVersion(colors, blocks, BlockLayout::kVariableRate, kFixedWeightCodesVersion);
  stream[0] = 5;
  EXPECT_EQ(BlockColorDecoder::Open(stream, colors.size()).status().code(), StatusCode::kCorrupt);
}

// Every cut is refused (the groups end the stream) and every flip ends in a typed status or colors.
TEST(FixedWeightCodes, CutsAndFlipsFailCleanly) {
  const std::vector<Rgb8> colors = NoisyGradient(3000, 2);
  const auto blocks = *EncodeBlocks(colors, BlockLayout::kVariableRate, 8.0);
  const auto stream = *SerializeBlocksAsVersion(colors, blocks, BlockLayout::kVariableRate, kFixedWeightCodesVersion);
  for (size_t length = 0; length < stream.size(); ++length) {
    EXPECT_FALSE(BlockColorDecoder::Open(std::span(stream).first(length), colors.size()).ok()) << "cut at " << length;
  }
  std::mt19937 rng(6);
  for (int trial = 0; trial < 2000; ++trial) {
    auto flipped = stream;
    flipped[rng() % flipped.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
    const auto decoded = BlockColorDecoder::Open(flipped, colors.size());
    if (decoded.ok()) {
      EXPECT_EQ(decoded->DecodeAll().size(), colors.size());
    }
  }
}

// The fuzz seeds of version 6 hold the version 2 seeds' decoded colors (color_fuzz_input.h's layout).
TEST(FixedWeightCodes, FuzzSeedsHoldTheVersionTwoSeedsColors) {
  for (const char* name : {"color_vbr/vbrquality34coderzstd", "color_fixed3/fixed3quality34"}) {
    const std::filesystem::path base = std::filesystem::path(POINTDAG_SOURCE_DIR) / "fuzz/seeds" / name;
    const std::vector<uint8_t> v2 = testing::ReadBytes(base.string() + "_v2.bin");
    const std::vector<uint8_t> v6 = testing::ReadBytes(base.string() + "_v6.bin");
    ASSERT_GT(v6.size(), 4u) << name;
    EXPECT_EQ(v6[3], 6);
    ASSERT_EQ(std::vector<uint8_t>(v2.begin(), v2.begin() + 3), std::vector<uint8_t>(v6.begin(), v6.begin() + 3));
    const uint64_t count = uint64_t{v2[0]} | uint64_t{v2[1]} << 8 | uint64_t{v2[2]} << 16;
    const auto old = BlockColorDecoder::Open(std::span(v2).subspan(3), count);
    const auto grouped = BlockColorDecoder::Open(std::span(v6).subspan(3), count);
    ASSERT_TRUE(old.ok() && grouped.ok()) << grouped.status().ToString();
    EXPECT_EQ(grouped->DecodeAll(), old->DecodeAll()) << name;
  }
}

}  // namespace
}  // namespace pointdag
