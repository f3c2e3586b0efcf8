#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>

#include "pointdag/dag/dag_builder.h"
#include "pointdag/dag/dag_stream.h"
#include "pointdag/entropy/binary_range_coder.h"
#include "pointdag/entropy/varint.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::SurfaceVoxels;

// A stream of fuzz/seeds/dag_stream (empty when missing: the tests then fail on it).
std::vector<uint8_t> ReadSeed(const std::string& name) {
  std::ifstream in(std::string(POINTDAG_SOURCE_DIR) + "/fuzz/seeds/dag_stream/" + name, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

Svdag Build(int depth, size_t voxels, uint32_t seed, CountMode mode = CountMode::kLeaves) {
  DagBuildOptions options;
  options.mode = mode;
  return BuildDag(SurfaceVoxels(depth, voxels, seed), depth, options).value();
}

TEST(BinaryRangeCoder, RoundTripsModelledAndDirectBits) {
  std::mt19937 rng(1);
  std::vector<int> bits(20000);
  std::vector<uint32_t> direct(2000);
  for (auto& b : bits) b = (rng() % 10) < 2;  // skewed: the model must learn it
  for (auto& d : direct) d = rng() & 0x1FFF;
  BinaryRangeEncoder enc;
  BitModel models[4];
  for (size_t i = 0; i < bits.size(); ++i) enc.Encode(models[i % 4], bits[i]);
  for (uint32_t d : direct) enc.EncodeDirect(d, 13);
  const auto bytes = enc.Finish();
  EXPECT_LT(bytes.size(), 20000 / 8 * 0.8 + 2000 * 13 / 8 + 16);  // skewed bits cost < 0.8 bit each
  BinaryRangeDecoder dec(bytes);
  BitModel dmodels[4];
  for (size_t i = 0; i < bits.size(); ++i) ASSERT_EQ(dec.Decode(dmodels[i % 4]), bits[i]) << i;
  for (uint32_t d : direct) ASSERT_EQ(dec.DecodeDirect(13), d);
  EXPECT_FALSE(dec.overrun());
}

// Version 8's ends: no leading zero byte, and a flush of the fewest bytes, zeros past the end read
// back as the value flushed; the same bits come back, 4 to 5 bytes fewer than Finish() writes.
TEST(BinaryRangeCoder, CompactEndsDecodeTheSameBits) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<int> bits(rng() % 300);
    for (auto& b : bits) b = (rng() % 16) < 3;
    BinaryRangeEncoder full, compact;
    YoungBitModel a[3], b[3];
    for (size_t i = 0; i < bits.size(); ++i) {
      full.Encode(a[i % 3], bits[i]);
      compact.Encode(b[i % 3], bits[i]);
    }
    const auto long_form = full.Finish();
    const auto bytes = compact.FinishCompact();
    EXPECT_GE(long_form.size() - bytes.size(), 4u);
    EXPECT_LE(long_form.size() - bytes.size(), 5u);
    EXPECT_EQ(long_form.at(0), 0);
    BinaryRangeDecoder dec(bytes, true);
    YoungBitModel c[3];
    for (size_t i = 0; i < bits.size(); ++i) ASSERT_EQ(dec.Decode(c[i % 3]), bits[i]) << "trial " << trial << " bit " << i;
    EXPECT_FALSE(dec.overrun());
  }
  EXPECT_TRUE(BinaryRangeEncoder().FinishCompact().empty());
}

struct StreamCase {
  int depth;
  CountMode mode;
  GeometryCoder coder;
};

class DagStreamTest : public ::testing::TestWithParam<StreamCase> {};

TEST_P(DagStreamTest, DecodesToTheIdenticalResidentDag) {
  const auto [depth, mode, coder] = GetParam();
  const Svdag dag = Build(depth, 20000, static_cast<uint32_t>(depth), mode);
  auto bytes = EncodeDag(dag, coder);
  ASSERT_TRUE(bytes.ok()) << bytes.status().ToString();
  auto decoded = DecodeDag(*bytes);
  ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
  EXPECT_EQ(*decoded, dag);
  // Far smaller than the resident form: no pointers for first-seen children.
  if (depth >= 8) {
    EXPECT_LT(bytes->size() * 2, dag.ResidentBytes());
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, DagStreamTest,
    ::testing::Values(StreamCase{2, CountMode::kLeaves, GeometryCoder::kZstd}, StreamCase{2, CountMode::kLeaves, GeometryCoder::kContext},
                      StreamCase{3, CountMode::kMipmap, GeometryCoder::kContext}, StreamCase{6, CountMode::kLeaves, GeometryCoder::kZstd},
                      StreamCase{10, CountMode::kLeaves, GeometryCoder::kZstd}, StreamCase{10, CountMode::kLeaves, GeometryCoder::kContext},
                      StreamCase{10, CountMode::kMipmap, GeometryCoder::kZstd}, StreamCase{10, CountMode::kMipmap, GeometryCoder::kContext},
                      StreamCase{16, CountMode::kLeaves, GeometryCoder::kContext}, StreamCase{21, CountMode::kLeaves, GeometryCoder::kZstd},
                      StreamCase{2, CountMode::kLeaves, GeometryCoder::kSpatial}, StreamCase{3, CountMode::kMipmap, GeometryCoder::kSpatial},
                      StreamCase{10, CountMode::kLeaves, GeometryCoder::kSpatial}, StreamCase{10, CountMode::kMipmap, GeometryCoder::kSpatial},
                      StreamCase{16, CountMode::kLeaves, GeometryCoder::kSpatial}, StreamCase{21, CountMode::kLeaves, GeometryCoder::kSpatial}));

TEST(DagStream, RepeatedSubtreesBecomeBackReferences) {
  std::vector<uint64_t> cube(4096);
  for (uint64_t i = 0; i < cube.size(); ++i) cube[i] = i;
  const Svdag dag = BuildDag(cube, 4).value();
  for (GeometryCoder coder : {GeometryCoder::kZstd, GeometryCoder::kContext, GeometryCoder::kSpatial}) {
    auto bytes = EncodeDag(dag, coder);
    ASSERT_TRUE(bytes.ok());
    EXPECT_EQ(DecodeDag(*bytes).value(), dag);
  }
}

// Corrupt or cut streams come back as errors, never as crashes or unbounded allocations.
TEST(DagStream, SurvivesTruncationAndBitFlips) {
  const Svdag dag = Build(9, 8000, 3);
  for (GeometryCoder coder : {GeometryCoder::kZstd, GeometryCoder::kContext, GeometryCoder::kSpatial}) {
    const auto bytes = EncodeDag(dag, coder).value();
    for (size_t len = 0; len < bytes.size(); len += 1 + bytes.size() / 300) {
      auto cut = DecodeDag(std::span(bytes).first(len));
      EXPECT_FALSE(cut.ok()) << GeometryCoderName(coder) << " decoded a stream cut at " << len;
    }
    std::mt19937 rng(7);
    for (int trial = 0; trial < 300; ++trial) {
      auto flipped = bytes;
      flipped[rng() % flipped.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
      auto decoded = DecodeDag(flipped);
      if (decoded.ok()) {
        EXPECT_TRUE(decoded->Validate().ok());  // a flip may still decode to some valid DAG
      }
    }
  }
}

// Versions 1 (coder 2 without edge neighbours), 2 (without the mixer), 3 (without the mixer's
// sides model), 4 (before the pattern models and height-3 slots) and 5 (before version 8's young
// flags, weights and compact framing) still decode: the fuzz seeds of tiny at 40 ft in all six
// versions hold one DAG, versions 3 to 5 re-encode byte for byte, and writers write version 8.
TEST(DagStream, SpatialVersions1To5StillDecode) {
  for (const std::string mode : {"leaves", "mipmap"}) {
    std::vector<std::vector<uint8_t>> streams = {ReadSeed(mode + "_spatial.bin")};
    for (int version : {2, 3, 4, 5, 8}) streams.push_back(ReadSeed(mode + "_spatial_v" + std::to_string(version) + ".bin"));
    const Svdag dag = DecodeDag(streams[0]).value();
    for (size_t i = 0; i < streams.size(); ++i) {
      const int version = i < 5 ? static_cast<int>(i) + 1 : 8;
      ASSERT_EQ(streams[i].at(0), version);
      EXPECT_EQ(DecodeDag(streams[i]).value(), dag) << "version " << version;
    }
    EXPECT_EQ(EncodeDag(dag, GeometryCoder::kSpatial, 3).value(), streams[2]);
    EXPECT_EQ(EncodeDag(dag, GeometryCoder::kSpatial, 4).value(), streams[3]);
    EXPECT_EQ(EncodeDag(dag, GeometryCoder::kSpatial, 5).value(), streams[4]);
    EXPECT_EQ(EncodeDag(dag, GeometryCoder::kSpatial).value(), streams[5]);
    EXPECT_LT(streams[1].size(), streams[0].size());
    EXPECT_LT(streams[2].size(), streams[1].size());
    EXPECT_LT(streams[4].size(), streams[3].size());  // (version 4 was 4 bytes above 3 on this small scan)
    EXPECT_EQ(streams[4].size() - streams[5].size(), 43u);  // 804 -> 761 bytes
  }
}

// The seeds `<mode><suffix>` (coder 3 in `version`) hold the DAG of version 5's seeds and are what the
// writer writes from it.
void ExpectSeedsHoldVersion5sDag(const std::string& suffix, int version) {
  for (const std::string mode : {"leaves", "mipmap"}) {
    const Svdag dag = DecodeDag(ReadSeed(mode + "_spatial_v5.bin")).value();
    const std::vector<uint8_t> stream = ReadSeed(mode + suffix);
    ASSERT_EQ(stream.at(0), version);
    ASSERT_EQ(stream.at(1), 3);
    EXPECT_EQ(DecodeDag(stream).value(), dag) << mode;
    EXPECT_EQ(EncodeDag(dag, GeometryCoder::kTable, version).value(), stream) << mode;
  }
}

// Random surfaces of depths 2..10 in both count modes, written by coder 3 in `version`, decode to
// themselves.
void ExpectTableCoderRoundTripsAtEveryDepth(int version, size_t voxels, uint32_t seed_offset) {
  for (int depth : {2, 3, 5, 8, 10}) {
    for (CountMode mode : {CountMode::kLeaves, CountMode::kMipmap}) {
      const Svdag dag = Build(depth, voxels, static_cast<uint32_t>(depth) + seed_offset, mode);
      const auto bytes = EncodeDag(dag, GeometryCoder::kTable, version).value();
      EXPECT_EQ(DecodeDag(bytes).value(), dag) << "depth " << depth;
    }
  }
}

// Every cut of `good` fails (the masks end the stream: no flush bytes to spare), and every one-bit
// flip ends in a typed status or a valid DAG.
void ExpectCutsFailAndFlipsStayValid(const std::vector<uint8_t>& good, uint32_t seed) {
  for (size_t length = 0; length < good.size(); ++length) {
    EXPECT_FALSE(DecodeDag(std::span(good).first(length)).ok()) << "cut at " << length;
  }
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 2000; ++trial) {
    auto flipped = good;
    flipped[rng() % flipped.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
    const auto decoded = DecodeDag(flipped);
    if (decoded.ok()) {
      EXPECT_TRUE(decoded->Validate().ok());
    }
  }
}

// Coder 3 (stream version 6, the tiles'): the seeds of tiny at 40 ft re-encoded with it hold the
// same DAG and are what the writer writes; random surfaces of every depth round-trip; version 6 and
// coder 3 come only together; every cut or flip ends in a typed status or a valid DAG.
TEST(DagStream, TableCoderRoundTrips) {
  ExpectSeedsHoldVersion5sDag("_table.bin", kTableStreamVersion);
  ExpectTableCoderRoundTripsAtEveryDepth(kTableStreamVersion, 3000, 0);
  const Svdag dag = Build(6, 2000, 4);
  EXPECT_EQ(EncodeDag(dag, GeometryCoder::kTable).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(EncodeDag(dag, GeometryCoder::kSpatial, kTableStreamVersion).status().code(), StatusCode::kInvalidArgument);
  const auto good = EncodeDag(dag, GeometryCoder::kTable, kTableStreamVersion).value();
  auto mismatched = good;
  mismatched[0] = 5;
  EXPECT_EQ(DecodeDag(mismatched).status().code(), StatusCode::kCorrupt);
  ExpectCutsFailAndFlipsStayValid(good, 6);
}

// Version 7 (coder 3, references in the prefix section; the tiles'): the seeds hold version 5's DAG
// and are what the writer writes; DAGs with many repeats (references of every length class) round-trip
// at every depth; the masks cost what version 6's cost; every cut or flip ends in a typed status or a
// valid DAG.
TEST(DagStream, PrefixCodedReferencesRoundTrip) {
  ExpectSeedsHoldVersion5sDag("_table_v7.bin", kPrefixRefsStreamVersion);
  ExpectTableCoderRoundTripsAtEveryDepth(kPrefixRefsStreamVersion, 6000, 40);
  EXPECT_EQ(EncodeDag(Build(6, 2000, 4), GeometryCoder::kSpatial, kPrefixRefsStreamVersion).status().code(), StatusCode::kInvalidArgument);
  const auto good = EncodeDag(Build(8, 4000, 9), GeometryCoder::kTable, kPrefixRefsStreamVersion).value();
  ExpectCutsFailAndFlipsStayValid(good, 7);
}

// Version 5 codes the nodes of height 3 at every occurrence and merges them back: a DAG in which
// they repeat (and bricks with them) comes back the same, and so does one whose every level repeats.
TEST(DagStream, SlotsOfHeightThreeMergeBackIntoTheDag) {
  std::vector<uint64_t> voxels;
  for (uint64_t block = 0; block < 64; ++block) {
    for (uint64_t v : {uint64_t{0}, uint64_t{9}, uint64_t{63}, uint64_t{300}}) voxels.push_back(block << 9 | v);  // one 8^3 pattern, 64 times
  }
  voxels.push_back(uint64_t{77} << 9 | 5);  // and one that differs
  std::sort(voxels.begin(), voxels.end());
  for (int depth : {3, 4, 5, 7}) {
    std::vector<uint64_t> inside;
    for (uint64_t v : voxels) {
      if (v < (uint64_t{1} << (3 * depth))) inside.push_back(v);
    }
    for (CountMode mode : {CountMode::kLeaves, CountMode::kMipmap}) {
      DagBuildOptions options;
      options.mode = mode;
      const Svdag dag = BuildDag(inside, depth, options).value();
      const auto bytes = EncodeDag(dag, GeometryCoder::kSpatial).value();
      EXPECT_EQ(DecodeDag(bytes).value(), dag) << "depth " << depth;
    }
  }
}

// A DAG decoded from a hostile older stream may store a node of height 3 twice; version 5's decoder
// would merge the two, so its encoder refuses such a DAG (as coder 2 refuses a repeated brick) and
// version 4 still writes it. (The fuzzer's find: fuzz/regressions/dag_stream/.)
TEST(DagStream, Version5RefusesARepeatedNodeOfHeightThree) {
  std::ifstream in(std::string(POINTDAG_SOURCE_DIR) + "/fuzz/regressions/dag_stream/v4_repeated_height3_node.bin", std::ios::binary);
  const std::vector<uint8_t> stream(std::istreambuf_iterator<char>(in), {});
  ASSERT_EQ(stream.at(0), 4);
  const Svdag dag = DecodeDag(stream).value();
  EXPECT_EQ(EncodeDag(dag, GeometryCoder::kSpatial).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(DecodeDag(EncodeDag(dag, GeometryCoder::kSpatial, 4).value()).value(), dag);
}

TEST(DagStream, RejectsLyingHeaders) {
  const auto good = EncodeDag(Build(6, 2000, 4), GeometryCoder::kContext).value();
  auto bad = good;
  bad[0] = 9;  // version
  EXPECT_EQ(DecodeDag(bad).status().code(), StatusCode::kCorrupt);
  bad = good;
  bad[1] = 7;  // coder
  EXPECT_EQ(DecodeDag(bad).status().code(), StatusCode::kCorrupt);
  bad = good;
  bad[2] = 30;  // depth
  EXPECT_EQ(DecodeDag(bad).status().code(), StatusCode::kCorrupt);
  // A level table claiming 2^40 nodes is refused before anything is allocated.
  std::vector<uint8_t> huge = {1, 1, 6, 0, 1};
  PutVarint(huge, uint64_t{1} << 40);
  EXPECT_EQ(DecodeDag(huge).status().code(), StatusCode::kCorrupt);
  EXPECT_EQ(DecodeDag(good, 10).status().code(), StatusCode::kCorrupt);  // caller's own bound
  EXPECT_EQ(DecodeDag(std::vector<uint8_t>{1, 0}).status().code(), StatusCode::kTruncated);
}

// Version 8's 2-byte header: depth and mode in one byte, its reserved bits zero; without a level
// table, the caller's bound on nodes is checked as they are decoded.
TEST(DagStream, Version8RejectsLyingHeaders) {
  const Svdag dag = Build(9, 8000, 5, CountMode::kMipmap);
  const auto good = EncodeDag(dag, GeometryCoder::kSpatial).value();
  ASSERT_EQ(good.at(0), 8);
  EXPECT_EQ(good.at(1), 9 | 1 << 5);
  EXPECT_EQ(DecodeDag(good).value(), dag);
  auto bad = good;
  bad[1] = 22 | 1 << 5;  // depth
  EXPECT_EQ(DecodeDag(bad).status().code(), StatusCode::kCorrupt);
  bad[1] = 1;
  EXPECT_EQ(DecodeDag(bad).status().code(), StatusCode::kCorrupt);
  bad[1] = 9 | 1 << 6;  // reserved
  EXPECT_EQ(DecodeDag(bad).status().code(), StatusCode::kCorrupt);
  EXPECT_EQ(DecodeDag(good, 100).status().code(), StatusCode::kCorrupt);  // caller's own bound
  EXPECT_EQ(DecodeDag(std::vector<uint8_t>{8}).status().code(), StatusCode::kTruncated);
  // Coders 0 and 1 have no version 8: asked for it, they write their version 5 stream.
  EXPECT_EQ(EncodeDag(dag, GeometryCoder::kContext).value(), EncodeDag(dag, GeometryCoder::kContext, 5).value());
  EXPECT_EQ(EncodeDag(dag, GeometryCoder::kTable, 8).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace pointdag
