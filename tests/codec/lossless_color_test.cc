// The lossless colors section (codec 1): versions 4 (written), 3 and 2, the context coders predicting
// from decoded neighbours (lossless_context.h), on edge cases and hostile bytes; version 1 (zstd)
// still decodes.
// The real scans' round trips are in color_test.cc (LosslessTest).
#include <gtest/gtest.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <set>
#include <utility>

#include "pointdag/color/causal_neighbours.h"
#include "pointdag/color/color_codec.h"
#include "pointdag/color/lossless_context.h"
#include "pointdag/entropy/varint.h"
#include "pointdag/voxelize/morton.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::SheetMorton;

std::vector<uint64_t> DenseMorton(size_t n) {
  std::vector<uint64_t> m(n);
  for (size_t i = 0; i < n; ++i) m[i] = i;
  return m;
}

std::vector<Rgb8> RandomColors(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Rgb8> c(n);
  for (auto& x : c) x = {static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng())};
  return c;
}

// The section of codec 1 with a version-2, -3 or -4 payload (version 4: the encoder's layout, or
// `layout`).
std::vector<uint8_t> LosslessSection(const std::vector<Rgb8>& colors, const std::vector<uint64_t>& morton, int version,
                                     std::optional<uint8_t> layout = std::nullopt) {
  auto payload = EncodeLosslessContext(colors, morton, version, layout);
  EXPECT_TRUE(payload.ok()) << payload.status().ToString();
  std::vector<uint8_t> section = payload.ok() ? *payload : std::vector<uint8_t>{};
  section.insert(section.begin(), static_cast<uint8_t>(ColorCodec::kLossless));
  return section;
}

void ExpectRoundTrip(const std::vector<Rgb8>& colors, const std::vector<uint64_t>& morton) {
  auto encoded = EncodeColors(colors, {ColorCodec::kLossless, std::nullopt}, morton);
  ASSERT_TRUE(encoded.ok()) << encoded.status().ToString();
  EXPECT_EQ(encoded->bytes, LosslessSection(colors, morton, kLosslessContextVersion));
  for (int version : {2, 3, 4}) {
    auto decoded = DecodeColors(LosslessSection(colors, morton, version), colors.size(), morton);
    ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
    EXPECT_EQ(*decoded, colors) << "version " << version;
  }
  // Every layout of version 4 (the columns with neighbours only).
  for (int layout : {0, 1, 2, 3, 4, 5, 8, 9, 10, 11, 12, 13}) {
    if (layout >= 8 && morton.empty()) continue;
    auto decoded = DecodeColors(LosslessSection(colors, morton, 4, static_cast<uint8_t>(layout)), colors.size(), morton);
    ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
    EXPECT_EQ(*decoded, colors) << "layout " << layout;
  }
}

// Voxels at several heights per (x, y) column whose colors depend on (x, y) alone, as an airborne
// scan's colors from an orthophoto: the encoder chooses the columns, and they pay.
TEST(LosslessColors, ColumnsPayWhereColorsFollowTheImage) {
  std::mt19937 rng(12);
  std::set<uint64_t> cloud;
  while (cloud.size() < 6000) {
    cloud.insert(MortonEncode(static_cast<uint32_t>(rng() % 96), static_cast<uint32_t>(rng() % 96), static_cast<uint32_t>(rng() % 64)));
  }
  const std::vector<uint64_t> morton(cloud.begin(), cloud.end());
  std::vector<Rgb8> colors(morton.size());
  for (size_t i = 0; i < morton.size(); ++i) {
    const auto [x, y, z] = MortonDecode(morton[i]);
    const auto wave = [](uint32_t v, uint32_t k) { return static_cast<uint8_t>(128 + 100 * std::sin(v * 0.1 * k)); };
    colors[i] = {wave(x, 1), wave(x + y, 2), wave(y, 3)};
  }
  const auto chosen = LosslessSection(colors, morton, 4);
  ASSERT_GT(chosen.size(), 5u);
  EXPECT_NE(chosen[5] & 8, 0) << "the layout byte after codec, version, mode and a 2-byte count";
  EXPECT_LT(chosen.size(), LosslessSection(colors, morton, 4, uint8_t{0}).size());
  EXPECT_LT(chosen.size(), LosslessSection(colors, morton, 3).size());
  ExpectRoundTrip(colors, morton);
}

// The bricks find what a search of every earlier voxel finds, at the grid's edges too.
TEST(LosslessColors, CausalNeighboursAreEveryEarlierVoxelInTheShell) {
  std::vector<uint64_t> clustered = SheetMorton(1500, 10);
  std::mt19937 rng(11);
  std::set<uint64_t> cloud(clustered.begin(), clustered.end());
  while (cloud.size() < 3000) cloud.insert(MortonEncode(static_cast<uint32_t>(rng() % 12), static_cast<uint32_t>(rng() % 12), static_cast<uint32_t>(rng() % 12)));
  const std::vector<uint64_t> morton(cloud.begin(), cloud.end());
  CausalNeighbours neighbours(morton);
  for (const auto& [inner, outer] : {std::pair{0, 2}, std::pair{2, 4}, std::pair{0, 4}}) {
    for (size_t i = 0; i < morton.size(); ++i) {
      std::set<std::pair<size_t, int>> found, expected;
      neighbours.ForEach(i, inner, outer, [&](size_t j, int d2) { EXPECT_TRUE(found.insert({j, d2}).second); });
      const auto [x, y, z] = MortonDecode(morton[i]);
      for (size_t j = 0; j < i; ++j) {
        const auto [a, b, c] = MortonDecode(morton[j]);
        const int64_t dx = int64_t{a} - x, dy = int64_t{b} - y, dz = int64_t{c} - z;
        const int64_t far = std::max({std::abs(dx), std::abs(dy), std::abs(dz)});
        if (far > inner && far <= outer) expected.insert({j, static_cast<int>(dx * dx + dy * dy + dz * dz)});
      }
      ASSERT_EQ(found, expected) << "voxel " << i << ", shell " << inner << ".." << outer;
    }
  }
}

TEST(LosslessColors, EdgeCasesRoundTripWithAndWithoutNeighbours) {
  for (const std::vector<uint64_t>& none : {std::vector<uint64_t>{}}) {
    ExpectRoundTrip({{1, 2, 3}}, none);
    ExpectRoundTrip(std::vector<Rgb8>(5000, Rgb8{7, 7, 7}), none);
    ExpectRoundTrip(RandomColors(3000, 1), none);
  }
  ExpectRoundTrip({{255, 0, 128}}, {MortonEncode(3, 4, 5)});
  ExpectRoundTrip(std::vector<Rgb8>(4096, Rgb8{0, 255, 0}), DenseMorton(4096));
  ExpectRoundTrip(RandomColors(4096, 2), DenseMorton(4096));
  const auto sheet = SheetMorton(3000, 3);
  ExpectRoundTrip(RandomColors(sheet.size(), 4), sheet);
  std::vector<Rgb8> smooth(sheet.size());
  for (size_t i = 0; i < sheet.size(); ++i) {
    const auto [x, y, z] = MortonDecode(sheet[i]);
    smooth[i] = {static_cast<uint8_t>(x * 4), static_cast<uint8_t>(y * 3 + z), static_cast<uint8_t>(250 - y)};
  }
  ExpectRoundTrip(smooth, sheet);
}

TEST(LosslessColors, FlatColorsCostAlmostNothingAndRandomOnesAboutRaw) {
  const auto morton = DenseMorton(1 << 15);
  const auto flat = EncodeColors(std::vector<Rgb8>(morton.size(), Rgb8{9, 8, 7}), {ColorCodec::kLossless, std::nullopt}, morton);
  EXPECT_LT(flat->bytes.size(), 128u);
  const auto random = EncodeColors(RandomColors(morton.size(), 5), {ColorCodec::kLossless, std::nullopt}, morton);
  EXPECT_LT(random->bytes.size(), 3 * morton.size() * 105 / 100);
}

TEST(LosslessColors, Version1ZstdSectionsStillDecode) {
  const std::vector<Rgb8> colors = {{10, 20, 30}, {11, 19, 35}, {200, 0, 255}};
  std::vector<uint8_t> planes;
  for (int ch = 0; ch < 3; ++ch) {
    for (size_t i = 0; i < colors.size(); ++i) {
      const auto at = [&](size_t k) { return ch == 0 ? colors[k].r : ch == 1 ? colors[k].g : colors[k].b; };
      planes.push_back(static_cast<uint8_t>(at(i) - (i ? at(i - 1) : 0)));
    }
  }
  std::vector<uint8_t> section(1 + ZSTD_compressBound(planes.size()));
  section[0] = static_cast<uint8_t>(ColorCodec::kLossless);
  section.resize(1 + ZSTD_compress(section.data() + 1, section.size() - 1, planes.data(), planes.size(), 19));
  auto decoded = DecodeColors(section, colors.size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
  EXPECT_EQ(*decoded, colors);
}

TEST(LosslessColors, OnlyKnownVersionsAreWrittenOrRead) {
  const auto morton = DenseMorton(100);
  const auto colors = RandomColors(morton.size(), 9);
  EXPECT_EQ(EncodeLosslessContext(colors, morton, 1).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EncodeLosslessContext(colors, morton, 5).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EncodeLosslessContext(colors, morton, 4, uint8_t{6}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EncodeLosslessContext(colors, {}, 4, uint8_t{8}).status().code(), StatusCode::kInvalidArgument);
  auto section = LosslessSection(colors, morton, 3);
  for (int version : {0, 1, 5, 255}) {
    section[1] = static_cast<uint8_t>(version);
    EXPECT_FALSE(DecodeColors(section, colors.size(), morton).ok()) << version;
  }
  // Version 4's layout byte (after codec, version, mode and the 1-byte count): orders 6 and 7,
  // bits above the columns' are no layout; columns without the voxels' codes are refused.
  section = LosslessSection(colors, morton, 4, uint8_t{8});
  for (int layout : {6, 7, 14, 15, 16, 255}) {
    section[4] = static_cast<uint8_t>(layout);
    EXPECT_EQ(DecodeColors(section, colors.size(), morton).status().code(), StatusCode::kCorrupt) << layout;
  }
  section = LosslessSection(colors, {}, 4, uint8_t{1});
  section[4] = 9;
  EXPECT_EQ(DecodeColors(section, colors.size()).status().code(), StatusCode::kCorrupt);
}

class LosslessHostileTest : public ::testing::TestWithParam<int> {};

TEST_P(LosslessHostileTest, HostileSectionsAreCleanErrors) {
  const auto morton = SheetMorton(2000, 6);
  std::vector<Rgb8> colors = RandomColors(morton.size(), 7);
  for (size_t i = 0; i < colors.size(); i += 3) colors[i] = {100, 100, 100};
  const auto section = LosslessSection(colors, morton, GetParam());

  // Neighbour mode needs the geometry's codes, and as many as there are colors.
  EXPECT_EQ(DecodeColors(section, colors.size()).status().code(), StatusCode::kCorrupt);
  EXPECT_EQ(DecodeColors(section, colors.size(), std::span(morton).first(10)).status().code(), StatusCode::kCorrupt);
  EXPECT_EQ(DecodeColors(section, colors.size() + 1, morton).status().code(), StatusCode::kCorrupt);
  // Every truncation, and trailing bytes, are refused: the stream must end where its colors do.
  for (size_t len = 1; len < section.size(); len += 1 + (len > 8 ? section.size() / 300 : 0)) {
    EXPECT_FALSE(DecodeColors(std::span(section).first(len), colors.size(), morton).ok()) << len;
  }
  auto longer = section;
  longer.push_back(0);
  EXPECT_EQ(DecodeColors(longer, colors.size(), morton).status().code(), StatusCode::kCorrupt);
  // Bit flips decode to a clean error or to some colors, never to a crash (ASan/UBSan builds).
  std::mt19937 rng(8);
  for (int trial = 0; trial < 200; ++trial) {
    auto bad = section;
    bad[1 + rng() % (bad.size() - 1)] ^= static_cast<uint8_t>(1u << (rng() % 8));
    auto decoded = DecodeColors(bad, colors.size(), morton);
    if (decoded.ok()) {
      EXPECT_EQ(decoded->size(), colors.size());
    }
  }
  // Unknown mode; a count the bytes cannot hold is refused before anything is allocated by it.
  auto bad_mode = section;
  bad_mode[2] = 7;
  EXPECT_EQ(DecodeColors(bad_mode, colors.size(), morton).status().code(), StatusCode::kCorrupt);
  const uint64_t huge = uint64_t{1} << 31;
  std::vector<uint8_t> lie = {static_cast<uint8_t>(ColorCodec::kLossless), static_cast<uint8_t>(GetParam()), 0};
  PutVarint(lie, huge);
  lie.insert(lie.end(), {0, 0, 0, 0, 0});
  EXPECT_EQ(DecodeColors(lie, huge).status().code(), StatusCode::kCorrupt);
}

INSTANTIATE_TEST_SUITE_P(Versions, LosslessHostileTest, ::testing::Values(2, 3, 4));

}  // namespace
}  // namespace pointdag
