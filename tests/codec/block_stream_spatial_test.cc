// Block color stream versions 3 and 4 (leaf mode): the weights' spatial contexts (color/weight_context.h),
// version 4's weight mixer (color/weight_mixer.h) and endpoints predicted from the neighbours.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <set>

#include "pointdag/color/block_codec.h"
#include "pointdag/color/block_stream.h"
#include "pointdag/color/block_target.h"
#include "pointdag/color/color_codec.h"
#include "pointdag/color/weight_context.h"
#include "pointdag/voxelize/morton.h"
#include "test_util.h"

namespace pointdag {
namespace {

// A wavy surface of voxels (two layers where it is steep, holes here and there) and colors that
// vary smoothly over it with noise: neighbours in 3D are near in color, as on a scan.
struct Surface {
  std::vector<uint64_t> morton;
  std::vector<Rgb8> colors;
};

Surface WavySurface(uint32_t side, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<std::pair<uint64_t, Rgb8>> voxels;
  std::normal_distribution<double> noise(0.0, 4.0);
  for (uint32_t x = 0; x < side; ++x) {
    for (uint32_t y = 0; y < side; ++y) {
      if (rng() % 11 == 0) continue;  // a hole
      const double h = 20 + 8 * std::sin(x / 9.0) + 6 * std::cos(y / 7.0);
      const auto ch = [&](double base) { return static_cast<uint8_t>(std::clamp(std::lround(base + noise(rng)), 0l, 255l)); };
      const Rgb8 c{ch(128 + 100 * std::sin(x / 23.0)), ch(128 + 90 * std::cos(y / 17.0)), ch(60 + h)};
      for (uint32_t z = static_cast<uint32_t>(h); z <= static_cast<uint32_t>(h) + (x % 5 == 0); ++z) {
        voxels.push_back({MortonEncode(x, y, z), c});
      }
    }
  }
  std::sort(voxels.begin(), voxels.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  Surface s;
  for (const auto& [code, color] : voxels) s.morton.push_back(code), s.colors.push_back(color);
  return s;
}

TEST(BlockStreamSpatial, VersionsTwoToFourDecodeToTheSameColorsEachInFewerBytes) {
  const Surface s = WavySurface(160, 1);  // ~27000 voxels: two macro blocks
  for (BlockLayout layout : {BlockLayout::kVariableRate, BlockLayout::kFixedRate}) {
    const auto blocks = *EncodeBlocks(s.colors, layout, 12.0);
    const auto v2 = *SerializeBlocks(s.colors, blocks, layout);
    const auto v3 = *SerializeBlocksAsVersion(s.colors, blocks, layout, 3, s.morton);
    const auto v4 = *SerializeBlocks(s.colors, blocks, layout, s.morton);
    ASSERT_EQ(v2[0], 2);
    ASSERT_EQ(v3[0], 3);
    ASSERT_EQ(v4[0], 4);
    EXPECT_LT(v3.size(), v2.size());
    EXPECT_LT(v4.size(), v3.size());
    auto old = BlockColorDecoder::Open(v2, s.colors.size());
    ASSERT_TRUE(old.ok()) << old.status().ToString();
    const std::vector<Rgb8> colors = old->DecodeAll();
    for (const auto* stream : {&v3, &v4}) {
      auto spatial = BlockColorDecoder::Open(*stream, s.colors.size(), s.morton);
      ASSERT_TRUE(spatial.ok()) << spatial.status().ToString();
      EXPECT_EQ(spatial->DecodeAll(), colors);
      // Random access after Open: one color at a time, without its neighbours.
      for (uint64_t i = 0; i < colors.size(); i += 13) ASSERT_EQ(spatial->At(i), colors[i]) << i;
    }
  }
}

// The colors SerializeBlocks reports are the ones the stream decodes to (the encoder measures its
// PSNR on them instead of decoding): every version, both layouts, weights chosen with and without
// a rate price (BlocksForTarget's blocks are priced and refitted).
TEST(BlockStreamSpatial, TheWriterRebuildsWhatTheDecoderDecodes) {
  const Surface s = WavySurface(160, 5);
  for (BlockLayout layout : {BlockLayout::kVariableRate, BlockLayout::kFixedRate}) {
    const auto priced = BlocksForTarget(s.colors, {}, layout, 36.0);
    ASSERT_TRUE(priced.ok()) << priced.status().ToString();
    for (const auto& blocks : {*EncodeBlocks(s.colors, layout, 12.0), priced->blocks}) {
      for (uint8_t version = 1; version <= kBlockStreamVersion; ++version) {
        if (!IsBlockStreamVersion(version)) continue;
        const std::span<const uint64_t> morton = HasSpatialContexts(version) ? std::span<const uint64_t>(s.morton) : std::span<const uint64_t>();
        std::vector<Rgb8> rebuilt;
        const auto stream = SerializeBlocksAsVersion(s.colors, blocks, layout, version, morton, &rebuilt);
        ASSERT_TRUE(stream.ok()) << stream.status().ToString();
        auto decoder = BlockColorDecoder::Open(*stream, s.colors.size(), morton);
        ASSERT_TRUE(decoder.ok()) << decoder.status().ToString();
        EXPECT_EQ(rebuilt, decoder->DecodeAll()) << "version " << int{version};
      }
    }
  }
}

// The bricks find what a search of every earlier voxel finds: Position's neighbours (the 26 around,
// else the cells two away) and Surroundings' (the 26 around a block's first voxels, before it), on a
// sparse cloud that touches the grid's lowest cells.
TEST(BlockStreamSpatial, WeightContextsAreEveryEarlierNeighbour) {
  std::mt19937 rng(5);
  const auto coordinate = [&rng] { return static_cast<uint32_t>(rng() % 16); };
  std::set<uint64_t> cloud;  // 22 % of the cells: some voxels have only the cells two away before them
  while (cloud.size() < 900) cloud.insert(MortonEncode(coordinate(), coordinate(), coordinate()));
  const std::vector<uint64_t> morton(cloud.begin(), cloud.end());
  std::vector<Rgb8> decoded(morton.size());
  for (Rgb8& c : decoded) c = {static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng())};
  // Weighted sums of the voxels before `limit` at Chebyshev distance `ring` (1 or 2) from voxel i.
  const auto naive = [&](size_t i, size_t limit, int ring) {
    std::array<int64_t, 4> sum{};  // r, g, b, weight
    const auto [x, y, z] = MortonDecode(morton[i]);
    for (size_t j = 0; j < limit; ++j) {
      const auto [a, b, c] = MortonDecode(morton[j]);
      const int dx = static_cast<int>(a) - static_cast<int>(x), dy = static_cast<int>(b) - static_cast<int>(y),
                dz = static_cast<int>(c) - static_cast<int>(z);
      if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
      const int d2 = dx * dx + dy * dy + dz * dz;
      const int w = ring == 1 ? 8 >> ((dx != 0) + (dy != 0) + (dz != 0)) : d2 == 4 ? 3 : d2 <= 6 ? 2 : 1;
      sum[0] += w * decoded[j].r, sum[1] += w * decoded[j].g, sum[2] += w * decoded[j].b, sum[3] += w;
    }
    return sum;
  };
  const Endpoints ends{{10, 20, 30}, {240, 200, 90}};
  const int bits = 3;
  WeightContexts contexts(morton);
  size_t far_found = 0;
  for (size_t i = 0; i < morton.size(); ++i) {
    if (i % 7 == 0) {  // blocks of 7 voxels tile the colors
      const uint32_t length = static_cast<uint32_t>(std::min<size_t>(7, morton.size() - i));
      std::array<int64_t, 4> expected{};
      for (size_t k = i; k < i + length; ++k) {
        const auto near = naive(k, i, 1);
        for (int c = 0; c < 4; ++c) expected[c] += near[c];
      }
      const BlockSurroundings s = contexts.Surroundings(i, length);
      ASSERT_EQ((std::array<int64_t, 4>{s.r, s.g, s.b, s.weight}), expected) << "block at " << i;
    }
    auto sum = naive(i, i, 1);
    const bool far = sum[3] == 0;
    if (far) sum = naive(i, i, 2);
    const NeighbourPosition p = contexts.Position(i, ends, bits, true);
    ASSERT_EQ(p.found, sum[3] > 0) << "voxel " << i;
    ASSERT_EQ(p.far, far && p.found) << "voxel " << i;
    far_found += p.far ? 1 : 0;
    if (p.found) {  // the projection as weight_context.h documents it, from the naive sums
      const int64_t m = (1 << bits) - 1, sr = 230, sg = 180, sb = 60, len2 = sr * sr + sg * sg + sb * sb;
      const int64_t dot = (sum[0] - sum[3] * 10) * sr + (sum[1] - sum[3] * 20) * sg + (sum[2] - sum[3] * 30) * sb;
      const int64_t unit = 2 * sum[3] * len2;
      EXPECT_EQ(p.step, dot <= 0 ? 0 : std::min(m, (2 * dot * m + sum[3] * len2) / unit)) << "voxel " << i;
      EXPECT_EQ(p.half_step, dot <= 0 ? 0 : std::min(2 * m, (4 * dot * m + sum[3] * len2) / unit)) << "voxel " << i;
    }
    contexts.Record(i, decoded[i]);
  }
  EXPECT_GT(far_found, 10u);
}

TEST(BlockStreamSpatial, IsRefusedWithoutTheVoxelsMortonCodes) {
  const Surface s = WavySurface(40, 2);
  const auto blocks = *EncodeBlocks(s.colors, BlockLayout::kVariableRate, 12.0);
  const std::span<const uint64_t> fewer(s.morton.data(), s.morton.size() - 1);
  for (const uint8_t version : {uint8_t{3}, uint8_t{4}}) {
    const auto stream = *SerializeBlocksAsVersion(s.colors, blocks, BlockLayout::kVariableRate, version, s.morton);
    const auto missing = BlockColorDecoder::Open(stream, s.colors.size()).status();
    EXPECT_EQ(missing.code(), StatusCode::kCorrupt) << missing.ToString();
    EXPECT_EQ(BlockColorDecoder::Open(stream, s.colors.size(), fewer).status().code(), StatusCode::kCorrupt);
    EXPECT_FALSE(SerializeBlocksAsVersion(s.colors, {}, BlockLayout::kVariableRate, version, fewer).ok());
  }
}

TEST(BlockStreamSpatial, CorruptStreamsAreErrorsNotCrashes) {
  const Surface s = WavySurface(60, 3);
  const auto blocks = *EncodeBlocks(s.colors, BlockLayout::kVariableRate, 10.0);
  for (const uint8_t version : {uint8_t{3}, uint8_t{4}}) {
    const auto stream = *SerializeBlocksAsVersion(s.colors, blocks, BlockLayout::kVariableRate, version, s.morton);
    for (size_t len = 0; len < stream.size(); len += 1 + stream.size() / 200) {
      EXPECT_FALSE(BlockColorDecoder::Open(std::span(stream).first(len), s.colors.size(), s.morton).ok()) << len;
    }
    std::mt19937 rng(4);
    for (int trial = 0; trial < 300; ++trial) {
      auto bad = stream;
      bad[rng() % bad.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
      auto decoder = BlockColorDecoder::Open(bad, s.colors.size(), s.morton);
      if (decoder.ok()) {
        for (uint64_t i = 0; i < decoder->size(); i += 97) (void)decoder->At(i);  // in bounds, whatever it holds
      }
    }
  }
}

// Leaf-mode sections (Morton codes given) are version 4, mipmap ones (none) version 2; both decode.
TEST(BlockStreamSpatial, ColorSectionsPickTheirVersionByTheMortonCodes) {
  const Surface s = WavySurface(50, 5);
  for (ColorCodec codec : {ColorCodec::kVariableRate, ColorCodec::kFixedRate}) {
    auto leaf = EncodeColors(s.colors, {codec, 36.0}, s.morton);
    auto mip = EncodeColors(s.colors, {codec, 36.0});
    ASSERT_TRUE(leaf.ok() && mip.ok());
    EXPECT_EQ(leaf->bytes[1], 4);
    EXPECT_EQ(mip->bytes[1], 2);
    EXPECT_GE(leaf->psnr.y, 36.0);
    EXPECT_EQ(*DecodeColors(leaf->bytes, s.colors.size(), s.morton), *DecodeColors(mip->bytes, s.colors.size()));
  }
}

// The fuzz seeds of versions 3 and 4 hold the version 2 seeds' decoded colors, re-encoded exactly, for
// voxels 0..count-1 in Morton order (the dense block the color fuzz targets give: color_fuzz_input.h).
TEST(BlockStreamSpatial, FuzzSeedsHoldTheVersionTwoSeedsColors) {
  for (const char* name : {"color_vbr/vbrquality34coderzstd", "color_fixed3/fixed3quality34"}) {
    const std::filesystem::path base = std::filesystem::path(POINTDAG_SOURCE_DIR) / "fuzz/seeds" / name;
    const auto seed = [&](const char* suffix) { return testing::ReadBytes(base.string() + suffix); };
    const std::vector<uint8_t> v2 = seed("_v2.bin");
    ASSERT_GT(v2.size(), 4u) << name;
    const uint64_t count = uint64_t{v2[0]} | uint64_t{v2[1]} << 8 | uint64_t{v2[2]} << 16;
    std::vector<uint64_t> morton(count);
    for (uint64_t i = 0; i < count; ++i) morton[i] = i;
    auto old = BlockColorDecoder::Open(std::span(v2).subspan(3), count);
    ASSERT_TRUE(old.ok()) << old.status().ToString();
    const std::vector<Rgb8> colors = old->DecodeAll();
    for (const uint8_t version : {uint8_t{3}, uint8_t{4}}) {
      const std::vector<uint8_t> stream = seed(version == 3 ? "_v3.bin" : "_v4.bin");
      ASSERT_GT(stream.size(), 4u) << name;
      EXPECT_EQ(stream[3], version);
      auto spatial = BlockColorDecoder::Open(std::span(stream).subspan(3), count, morton);
      ASSERT_TRUE(spatial.ok()) << spatial.status().ToString();
      EXPECT_EQ(spatial->DecodeAll(), colors) << name << " version " << int{version};
    }
  }
}

}  // namespace
}  // namespace pointdag
