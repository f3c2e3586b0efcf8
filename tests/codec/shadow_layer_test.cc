// The per-tile shadow layer (proto/SHADOW_FORMAT.md §2): round trips, every malformed case refused
// with a typed Status, and coarse light = the mean of the fine lit fractions on a hand-made grid.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <random>

#include "pointdag/container/crc32c.h"
#include "pointdag/shadow/shadow_layer.h"
#include "pointdag/tile/tiler.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

std::vector<uint8_t> Encode(const ShadowLayer& layer) {
  auto bytes = EncodeShadowLayer(layer);
  EXPECT_TRUE(bytes.ok()) << bytes.status().ToString();
  return bytes.ok() ? *bytes : std::vector<uint8_t>{};
}

// Rewrites the CRC so that a test reaches the check after it.
void Reseal(std::vector<uint8_t>& bytes) {
  const uint32_t crc = Crc32c(std::span<const uint8_t>(bytes).subspan(kShadowLayerHeaderBytes));
  for (int i = 0; i < 4; ++i) bytes[12 + static_cast<size_t>(i)] = static_cast<uint8_t>(crc >> (8 * i));
}

TEST(ShadowLayer, RoundTripsRunsOfEveryLength) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    ShadowLayer layer{ShadowKind::kSunHours, 1 + trial * 29, {}};
    const size_t n = 1 + rng() % 5000;
    while (layer.light.size() < n) {
      const size_t run = std::min<size_t>(n - layer.light.size(), 1 + rng() % (trial % 2 ? 300 : 3));
      layer.light.insert(layer.light.end(), run, static_cast<uint8_t>(rng()));
    }
    const auto bytes = Encode(layer);
    const auto back = DecodeShadowLayer(bytes, n);
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    EXPECT_EQ(back->light, layer.light);
    EXPECT_EQ(back->kind, layer.kind);
    EXPECT_EQ(back->samples, layer.samples);
  }
  // A run longer than 128 voxels takes a two-byte varint; 70000 voxels of one value, three bytes.
  const ShadowLayer flat{ShadowKind::kDirection, 1, std::vector<uint8_t>(70000, 255)};
  const auto bytes = Encode(flat);
  EXPECT_EQ(bytes.size(), kShadowLayerHeaderBytes + 1 + 3);
  EXPECT_EQ(DecodeShadowLayer(bytes, 70000)->light, flat.light);
}

TEST(ShadowLayer, TheEncoderRefusesWhatTheFormatCannotHold) {
  EXPECT_EQ(EncodeShadowLayer({ShadowKind::kDirection, 1, {}}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EncodeShadowLayer({ShadowKind::kDirection, 2, {1}}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EncodeShadowLayer({ShadowKind::kSunHours, 0, {1}}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EncodeShadowLayer({ShadowKind::kSunHours, 1441, {1}}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EncodeShadowLayer({static_cast<ShadowKind>(2), 1, {1}}).status().code(), StatusCode::kInvalidArgument);
}

// A layer's bytes with `body` after a header of `version` (CRC computed).
std::vector<uint8_t> WithBody(uint8_t version, ShadowKind kind, int samples, uint32_t n, const std::vector<uint8_t>& body) {
  const uint8_t header[] = {'P', 'D', 'S', 'H', version, static_cast<uint8_t>(kind), static_cast<uint8_t>(samples),
                            static_cast<uint8_t>(samples >> 8), static_cast<uint8_t>(n), static_cast<uint8_t>(n >> 8),
                            static_cast<uint8_t>(n >> 16), static_cast<uint8_t>(n >> 24), 0, 0, 0, 0};
  std::vector<uint8_t> bytes(std::begin(header), std::end(header));
  bytes.resize(kShadowLayerHeaderBytes + body.size());
  std::copy(body.begin(), body.end(), bytes.begin() + kShadowLayerHeaderBytes);
  Reseal(bytes);
  return bytes;
}

struct Damage {
  const char* what;
  std::function<void(std::vector<uint8_t>&)> damage;
  StatusCode code;
  uint64_t voxels = 10;
};

void ExpectRefused(const std::vector<uint8_t>& good, const std::vector<Damage>& cases) {
  ASSERT_TRUE(DecodeShadowLayer(good, 10).ok());
  for (const Damage& c : cases) {
    std::vector<uint8_t> bytes = good;
    c.damage(bytes);
    const auto decoded = DecodeShadowLayer(bytes, c.voxels);
    ASSERT_FALSE(decoded.ok()) << c.what;
    EXPECT_EQ(decoded.status().code(), c.code) << c.what << ": " << decoded.status().ToString();
  }
}

const std::vector<uint8_t> kLight = {0, 0, 0, 9, 9, 255, 7, 7, 7, 7};

TEST(ShadowLayer, TheWriterUsesRunsFromThreeAndLiteralStringsBetween) {
  // 0 x3 -> token 4, value 0; 9 9 255 -> token 5 and the three bytes; 7 x4 -> token 6, value 7.
  EXPECT_EQ(Encode({ShadowKind::kSunHours, 12, kLight}), WithBody(2, ShadowKind::kSunHours, 12, 10, {4, 0, 5, 9, 9, 255, 6, 7}));
  // Worst case: no two neighbours alike, about a byte a voxel.
  std::mt19937 rng(11);
  ShadowLayer noisy{ShadowKind::kSunHours, 48, std::vector<uint8_t>(5000)};
  for (uint8_t& v : noisy.light) v = static_cast<uint8_t>(rng());
  EXPECT_LE(Encode(noisy).size(), kShadowLayerHeaderBytes + 5000 * 105 / 100 + 8);
}

TEST(ShadowLayer, EveryMalformedCaseOfTheSpecIsRefused) {
  const std::vector<uint8_t> good = Encode({ShadowKind::kSunHours, 12, kLight});  // body 4 0 5 9 9 255 6 7
  ExpectRefused(good, {
      {"shorter than the header", [](auto& b) { b.resize(15); }, StatusCode::kTruncated},
      {"empty", [](auto& b) { b.clear(); }, StatusCode::kTruncated},
      {"wrong magic", [](auto& b) { b[0] = 'X'; }, StatusCode::kMalformed},
      {"version 0", [](auto& b) { b[4] = 0; }, StatusCode::kMalformed},
      {"version 3", [](auto& b) { b[4] = 3; }, StatusCode::kMalformed},
      {"unknown kind", [](auto& b) { b[5] = 2; }, StatusCode::kMalformed},
      {"samples 0", [](auto& b) { b[6] = b[7] = 0; }, StatusCode::kMalformed},
      {"samples 1441", [](auto& b) { b[6] = 1441 & 0xFF, b[7] = 1441 >> 8; }, StatusCode::kMalformed},
      {"one direction with 12 samples", [](auto& b) { b[5] = 0; }, StatusCode::kMalformed},
      {"n other than the tile's", [](auto& b) { b[8] = 11; }, StatusCode::kMalformed},
      {"the tile's count other than n", [](auto&) {}, StatusCode::kMalformed, 9},
      {"n = 0", [](auto& b) { b[8] = 0; }, StatusCode::kMalformed, 0},
      {"a huge n", [](auto& b) { b[8] = b[9] = b[10] = b[11] = 0xFF; }, StatusCode::kMalformed},
      {"a CRC mismatch", [](auto& b) { b[17] ^= 1; }, StatusCode::kCorrupt},
      {"a run passing n", [](auto& b) { b[16] = 50, Reseal(b); }, StatusCode::kMalformed},
      {"a literal string passing n", [](auto& b) { b[18] = 41, Reseal(b); }, StatusCode::kMalformed},
      {"the body ending before n", [](auto& b) { b.resize(b.size() - 2), Reseal(b); }, StatusCode::kTruncated},
      {"a run without its value", [](auto& b) { b.resize(b.size() - 1), Reseal(b); }, StatusCode::kTruncated},
      {"a literal string cut short", [](auto& b) { b.resize(kShadowLayerHeaderBytes + 4), Reseal(b); }, StatusCode::kTruncated},
      {"a token cut short", [](auto& b) { b.resize(kShadowLayerHeaderBytes + 6), b.push_back(0x80), Reseal(b); }, StatusCode::kTruncated},
      {"a token over 10 bytes",
       [](auto& b) { b.resize(kShadowLayerHeaderBytes), b.insert(b.end(), 11, 0xFF), Reseal(b); }, StatusCode::kTruncated},
      {"a token of 2^64 - 1",
       [](auto& b) { b.resize(kShadowLayerHeaderBytes), b.insert(b.end(), 9, 0xFF), b.push_back(0x01), Reseal(b); },
       StatusCode::kMalformed},
      {"bytes after the last run", [](auto& b) { b.push_back(0), Reseal(b); }, StatusCode::kMalformed},
  });
}

// Version 1 (runs only) is still read: layers a daemon stored before version 2.
TEST(ShadowLayer, VersionOneRunsAreReadAndCheckedAlike) {
  const std::vector<uint8_t> v1 = WithBody(1, ShadowKind::kSunHours, 12, 10, {0, 2, 9, 1, 255, 0, 7, 3});
  const auto decoded = DecodeShadowLayer(v1, 10);
  ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
  EXPECT_EQ(decoded->light, kLight);
  ExpectRefused(v1, {
      {"a run passing n", [](auto& b) { b[17] = 50, Reseal(b); }, StatusCode::kMalformed},
      {"runs ending before n", [](auto& b) { b.resize(b.size() - 2), Reseal(b); }, StatusCode::kTruncated},
      {"a run length cut short", [](auto& b) { b.back() = 0x80, Reseal(b); }, StatusCode::kTruncated},
      {"a run length of 2^64 - 1",
       [](auto& b) { b.resize(kShadowLayerHeaderBytes + 1), b.insert(b.end(), 9, 0xFF), b.push_back(0x01), Reseal(b); },
       StatusCode::kMalformed},
      {"bytes after the last run", [](auto& b) { b.push_back(0), Reseal(b); }, StatusCode::kMalformed},
  });
}

TEST(ShadowLayer, NonMaximalRunsAreRead) {
  // Two runs of the same value one after the other, and a literal string of equal bytes: legal, read as written.
  for (const auto& bytes : {WithBody(2, ShadowKind::kDirection, 1, 5, {0, 4, 2, 4, 3, 4, 4}),
                            WithBody(1, ShadowKind::kDirection, 1, 5, {4, 0, 4, 1, 4, 1})}) {
    const auto decoded = DecodeShadowLayer(bytes, 5);
    ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
    EXPECT_EQ(decoded->light, (std::vector<uint8_t>{4, 4, 4, 4, 4}));
  }
}

TEST(ShadowLayer, LightByteRoundsHalfUpExactly) {
  EXPECT_EQ(LightByte(0, 5, 7), 0);
  EXPECT_EQ(LightByte(35, 5, 7), 255);
  EXPECT_EQ(LightByte(1, 2, 1), 128);  // 127.5
  EXPECT_EQ(LightByte(1, 3, 1), 85);   // 85.0
  EXPECT_EQ(LightByte(2, 3, 1), 170);
  EXPECT_EQ(LightByte(1, 1, 1440), 0);   // 0.177
  EXPECT_EQ(LightByte(3, 1, 1440), 1);   // 0.53
  EXPECT_EQ(LightByte(uint64_t{1} << 40, uint64_t{1} << 40, 1), 255);
}

// A hand-made depth-10 grid (three levels of 256^3 tiles): every tile's byte is the exact mean of
// the finest lit fractions it covers, and the tiles are those tiler.h cuts, voxel for voxel.
TEST(ShadowLayer, CoarseLightIsTheMeanOfTheFineVoxelsItCovers) {
  const int depth = 10, samples = 6;
  std::map<uint64_t, uint16_t> voxels;
  std::mt19937 rng(3);
  for (int i = 0; i < 20000; ++i) {
    const uint32_t x = rng() % 1024, y = rng() % 1024, z = ((x + y) / 2 + rng() % 4) % 1024;
    voxels[MortonEncode(x, y, z)] = static_cast<uint16_t>(rng() % (samples + 1));
  }
  // A cluster of 8 finest voxels in one level-1 voxel with known counts 0..6 and 6: mean 27/48.
  for (uint32_t k = 0; k < 8; ++k) voxels[MortonEncode(2 + (k & 1), 4 + (k >> 1 & 1), 1000 + (k >> 2))] = static_cast<uint16_t>(std::min<uint32_t>(k, 6));
  VoxelGrid finest;
  finest.depth = depth;
  std::vector<uint16_t> counts;
  for (const auto& [code, lit] : voxels) finest.morton.push_back(code), counts.push_back(lit);
  const auto layers = ComputeTileLayers(finest.morton, depth, counts, ShadowKind::kSunHours, samples, 8);
  ASSERT_TRUE(layers.ok()) << layers.status().ToString();

  size_t checked = 0;
  for (int level = 0; level < 3; ++level) {
    const VoxelGrid grid = LevelGrid(finest, level, 8);
    const int shift = 3 * (2 - level);
    std::map<TileKey, std::vector<uint8_t>> expected;
    for (uint64_t code : grid.morton) {
      uint64_t lit = 0, n = 0;
      for (auto it = voxels.lower_bound(code << shift); it != voxels.end() && (it->first >> shift) == code; ++it) lit += it->second, ++n;
      const auto [x, y, z] = MortonDecode(code >> 24);
      expected[{level, x, y, z}].push_back(static_cast<uint8_t>(std::lround(255.0 * static_cast<double>(lit) / static_cast<double>(n * samples))));
    }
    for (const auto& [tile, light] : expected) {
      const TileKey key = tile;  // clang 14 cannot capture a structured binding
      const auto found = std::find_if(layers->begin(), layers->end(), [&](const TileShadowLayer& t) { return t.key == key; });
      ASSERT_NE(found, layers->end()) << "no layer for tile " << key.level << "/" << key.x << "/" << key.y << "/" << key.z;
      EXPECT_EQ(found->layer.light, light);
      ++checked;
    }
  }
  EXPECT_EQ(checked, layers->size());
  EXPECT_TRUE(std::is_sorted(layers->begin(), layers->end(), [](const auto& a, const auto& b) { return a.key < b.key; }));
  // The level-1 voxel of the cluster: (0+1+2+3+4+5+6+6) / (8 * 6) = 27/48 -> round(143.4) = 143.
  const auto root = std::find_if(layers->begin(), layers->end(), [](const auto& t) { return t.key == TileKey{1, 0, 0, 1}; });
  ASSERT_NE(root, layers->end());
  const auto cell = LevelGrid(finest, 1, 8);
  const uint64_t cluster = MortonEncode(1, 2, 500);
  const auto at = std::lower_bound(cell.morton.begin(), cell.morton.end(), cluster);
  ASSERT_TRUE(at != cell.morton.end() && *at == cluster);
  size_t index = 0;  // its rank within tile (1, 0, 0, 1)
  for (auto it = cell.morton.begin(); it != at; ++it) index += (*it >> 24) == (cluster >> 24);
  EXPECT_EQ(root->layer.light[index], 143);
}

TEST(ShadowLayer, ComputeRefusesInconsistentInputs) {
  const std::vector<uint64_t> codes = {1, 2, 3};
  const std::vector<uint16_t> counts = {0, 1, 1};
  EXPECT_TRUE(ComputeTileLayers(codes, 4, counts, ShadowKind::kDirection, 1, 8).ok());
  EXPECT_EQ(ComputeTileLayers(codes, 4, std::vector<uint16_t>{0, 1}, ShadowKind::kDirection, 1, 8).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ComputeTileLayers(codes, 4, std::vector<uint16_t>{0, 2, 1}, ShadowKind::kDirection, 1, 8).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ComputeTileLayers(std::vector<uint64_t>{3, 2, 1}, 4, counts, ShadowKind::kDirection, 1, 8).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ComputeTileLayers(codes, 4, counts, ShadowKind::kSunHours, 0, 8).status().code(), StatusCode::kInvalidArgument);
  // Depth 4 < tile depth 8: one level of one tile of 16^3 voxels.
  const auto one = ComputeTileLayers(codes, 4, counts, ShadowKind::kDirection, 1, 8);
  ASSERT_EQ(one->size(), 1u);
  EXPECT_EQ(one->front().key, (TileKey{0, 0, 0, 0}));
  EXPECT_EQ(one->front().layer.light, (std::vector<uint8_t>{0, 255, 255}));
}

}  // namespace
}  // namespace pointdag
