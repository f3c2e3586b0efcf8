// The layered LAZ chunk decoder (LAS 1.4 point formats 6-8: POINT14, RGB14, RGBNIR14, BYTE14) on
// the files of ../shared/data/laz: every chunk decodes to the records two independent LAZ
// implementations agree on (manifest.json's sha256, the matching .las where there is one), and
// damaged chunks (truncations, bit flips, lying sizes) end in a clean status.
#include <gtest/gtest.h>
#include <openssl/evp.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "pointdag/read/byte_io.h"
#include "pointdag/read/laz/chunk_decoder.h"
#include "pointdag/read/laz/laszip_vlr.h"
#include "pointdag/read/laz/laz_reader.h"
#include "pointdag/read/laz/layered_item_decoder.h"
#include "test_util.h"

namespace pointdag::laz {
namespace {

using pointdag::testing::ReadBytes;

std::filesystem::path LazDir() { return pointdag::testing::DataDir() / "laz"; }

#define SKIP_WITHOUT_LAZ_DATA()                                                           \
  do {                                                                                     \
    if (!std::filesystem::exists(LazDir() / "manifest.json"))                              \
      GTEST_SKIP() << "LAZ test files not found at " << LazDir() << "; skipping";          \
  } while (0)

std::string Sha256(const uint8_t* data, size_t size) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(data, size, digest, &length, EVP_sha256(), nullptr);
  std::string hex;
  char byte[3];
  for (unsigned int i = 0; i < length; ++i) {
    std::snprintf(byte, sizeof byte, "%02x", digest[i]);
    hex += byte;
  }
  return hex;
}

struct Chunk {
  uint64_t start = 0, size = 0, points = 0;
};

// A LAZ file's bytes, with its LASzip VLR and chunks as the reader (laz_reader.h) finds them.
struct LazFile {
  std::vector<uint8_t> bytes;
  LaszipVlr vlr;
  uint32_t record_length = 0;
  uint64_t points = 0;
  std::vector<Chunk> chunks;
};

LazFile OpenLaz(const std::string& name) {
  LazFile f;
  f.bytes = ReadBytes(LazDir() / name);
  auto reader = LazReader::Open(LazDir() / name);
  EXPECT_TRUE(reader.ok()) << reader.status().ToString();
  if (!reader.ok()) return f;
  f.vlr = (*reader)->vlr();
  f.record_length = (*reader)->record_length();
  const ChunkTable& table = (*reader)->chunks();
  EXPECT_FALSE(table.sequential) << name << " has a chunk table";
  for (size_t i = 0; i < table.size(); ++i) {
    f.chunks.push_back({table.starts[i], table.starts[i + 1] - table.starts[i], table.points[i]});
    f.points += table.points[i];
  }
  return f;
}

std::unique_ptr<ChunkDecoder> MakeDecoder(const LaszipVlr& vlr) {
  auto decoder = MakeChunkDecoder(vlr);
  EXPECT_TRUE(decoder.ok()) << decoder.status().ToString();
  return decoder.ok() ? std::move(*decoder) : nullptr;
}

// Decodes one chunk whole; the status of the first failure.
Status DecodeChunk(ChunkDecoder& decoder, const uint8_t* data, size_t size, uint64_t points, std::vector<uint8_t>& out,
                   uint32_t record_length) {
  out.resize(points * record_length);
  RETURN_IF_ERROR(decoder.Start(data, size, points));
  return decoder.Decode(out.data(), points);
}

// Every layered file of the manifest but the waveform one (refused by the VLR parser).
constexpr const char* kLayeredFiles[] = {
    "laspy_1_4_w_evlr.laz",                        // POINT14, matches its .las
    "laszip4j_record-format-7.laz",                // POINT14 RGB14 BYTE14:21
    "laszip4j_record-format-8.laz",                // POINT14 RGBNIR14 BYTE14:21
    "laszip4j_500m_5460_59370_IM2023_subset.laz",  // POINT14 RGB14, 2 chunks, all four scanner channels
    "laszip4j_2019_saipan_waveform.laz",           // POINT14 BYTE14:120
    "pdal_1.2-with-color.copc.laz",                // POINT14 RGB14, 65 variable chunks
    "laspy_simple_with_page.copc.laz",             // the same points, another COPC writer
    "pdal_lone-star.copc.laz",                     // POINT14, 15 variable chunks, 518,862 points
};

nlohmann::json ManifestEntry(const std::string& file) {
  std::ifstream in(LazDir() / "manifest.json");
  for (const auto& entry : nlohmann::json::parse(in)) {
    if (entry["file"] == file) return entry;
  }
  ADD_FAILURE() << file << " is not in manifest.json";
  return {};
}

class LayeredOracle : public ::testing::TestWithParam<const char*> {};

// Every chunk, decoded by one reused decoder, and the records hash to the oracle's sha256. Fixed
// chunks also chain: each starts where the one before ended by BytesUsed().
TEST_P(LayeredOracle, RecordsMatchTheManifest) {
  SKIP_WITHOUT_LAZ_DATA();
  const LazFile f = OpenLaz(GetParam());
  ASSERT_EQ(f.vlr.compressor, Compressor::kLayeredChunked);
  auto decoder = MakeDecoder(f.vlr);
  ASSERT_TRUE(decoder);
  std::vector<uint8_t> records, chunk;
  uint64_t points = 0;
  for (size_t i = 0; i < f.chunks.size(); ++i) {
    const Chunk& c = f.chunks[i];
    ASSERT_LE(c.start + c.size, f.bytes.size());
    const Status s = DecodeChunk(*decoder, f.bytes.data() + c.start, c.size, c.points, chunk, f.record_length);
    ASSERT_TRUE(s.ok()) << "chunk " << i << ": " << s.ToString();
    EXPECT_EQ(decoder->BytesUsed(), c.size) << "chunk " << i;
    records.insert(records.end(), chunk.begin(), chunk.end());
    points += c.points;
  }
  const nlohmann::json entry = ManifestEntry(GetParam());
  EXPECT_EQ(points, entry["points"].get<uint64_t>());
  EXPECT_EQ(Sha256(records.data(), records.size()), entry["decoded_points_sha256"].get<std::string>());
  if (entry.contains("reference_las") && entry["reference_las"].is_string()) {
    const auto las = ReadBytes(LazDir() / entry["reference_las"].get<std::string>());
    const uint32_t offset = LoadLE<uint32_t>(las.data() + 96);
    ASSERT_GE(las.size(), offset + records.size());
    EXPECT_TRUE(std::equal(records.begin(), records.end(), las.begin() + offset));
  }
}

INSTANTIATE_TEST_SUITE_P(Files, LayeredOracle, ::testing::ValuesIn(kLayeredFiles),
                         [](const auto& param) {
                           std::string name = param.param;
                           for (char& ch : name) {
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           }
                           return name;
                         });

// The first chunk of a file, and its records decoded whole (the reference for the tests below).
struct FirstChunk {
  LazFile file;
  std::vector<uint8_t> bytes;  // a copy: the tests damage it
  uint64_t points = 0;
};

FirstChunk TakeFirstChunk(const std::string& name) {
  FirstChunk fc{OpenLaz(name), {}, 0};
  const Chunk& c = fc.file.chunks.at(0);
  fc.bytes.assign(fc.file.bytes.begin() + static_cast<std::ptrdiff_t>(c.start),
                  fc.file.bytes.begin() + static_cast<std::ptrdiff_t>(c.start + c.size));
  fc.points = c.points;
  return fc;
}

TEST(LayeredChunk, BatchesOfAnySizeEqualOneBatch) {
  SKIP_WITHOUT_LAZ_DATA();
  const FirstChunk fc = TakeFirstChunk("laszip4j_record-format-8.laz");
  auto decoder = MakeDecoder(fc.file.vlr);
  ASSERT_TRUE(decoder);
  std::vector<uint8_t> whole;
  ASSERT_TRUE(DecodeChunk(*decoder, fc.bytes.data(), fc.bytes.size(), fc.points, whole, fc.file.record_length).ok());
  for (const size_t batch : {size_t{1}, size_t{7}, size_t{61}}) {
    std::vector<uint8_t> parts(whole.size());
    ASSERT_TRUE(decoder->Start(fc.bytes.data(), fc.bytes.size(), fc.points).ok());
    for (size_t at = 0; at < fc.points; at += batch) {
      const size_t n = std::min<size_t>(batch, fc.points - at);
      ASSERT_TRUE(decoder->Decode(parts.data() + at * fc.file.record_length, n).ok());
    }
    EXPECT_EQ(parts, whole) << "batches of " << batch;
    EXPECT_EQ(decoder->Decode(parts.data(), 1).code(), StatusCode::kInvalidArgument);  // none left
  }
}

// Files with one scanner channel decode the same as items version 4: the versions differ only in
// how a change of channel selects the colour and extra-byte contexts.
TEST(LayeredChunk, Version4EqualsVersion3OnOneChannel) {
  SKIP_WITHOUT_LAZ_DATA();
  for (const char* name : {"laszip4j_record-format-7.laz", "laszip4j_record-format-8.laz"}) {
    const FirstChunk fc = TakeFirstChunk(name);
    LaszipVlr v4 = fc.file.vlr;
    for (Item& item : v4.items) item.version = 4;
    std::vector<uint8_t> records3, records4;
    auto decoder3 = MakeDecoder(fc.file.vlr), decoder4 = MakeDecoder(v4);
    ASSERT_TRUE(decoder3 && decoder4);
    const uint32_t rl = fc.file.record_length;
    ASSERT_TRUE(DecodeChunk(*decoder3, fc.bytes.data(), fc.bytes.size(), fc.points, records3, rl).ok());
    ASSERT_TRUE(DecodeChunk(*decoder4, fc.bytes.data(), fc.bytes.size(), fc.points, records4, rl).ok());
    EXPECT_EQ(records3, records4) << name;
  }
}

// LASzip's rule for the items after POINT14: a context new in the chunk starts from the values of
// the one left; returning to a context already in use predicts, in version 3, from the context
// just left (LASzip 3.x's stale pointer), in version 4 from the context's own values.
TEST(LayeredChunk, ContextFollowerKeepsLaszipsVersionRule) {
  for (const uint16_t version : {uint16_t{3}, uint16_t{4}}) {
    ContextFollower follower(version);
    std::vector<std::pair<uint32_t, uint32_t>> inits;
    const auto init = [&inits](uint32_t to, uint32_t from) { inits.emplace_back(to, from); };
    follower.Start(1);
    EXPECT_EQ(follower.Follow(1, init), 1U);
    EXPECT_EQ(follower.Follow(0, init), 0U);  // new: starts from context 1's values
    EXPECT_EQ(follower.Follow(2, init), 2U);  // new: from context 0's
    EXPECT_EQ(follower.Follow(0, init), version == 3 ? 2U : 0U);
    EXPECT_EQ(follower.current(), 0U);
    EXPECT_EQ(follower.Follow(0, init), 0U);
    EXPECT_EQ(inits, (std::vector<std::pair<uint32_t, uint32_t>>{{0, 1}, {2, 0}}));
  }
}

TEST(LayeredChunk, ItemListsLaszipNeverWritesAreRefused) {
  const Item point{ItemType::kPoint14, 30, 3}, rgb{ItemType::kRgb14, 6, 3}, nir{ItemType::kRgbNir14, 8, 3},
      bytes{ItemType::kByte14, 5, 3}, wave{ItemType::kWavepacket14, 29, 3};
  LaszipVlr vlr;
  vlr.compressor = Compressor::kLayeredChunked;
  vlr.chunk_size = 50000;
  for (const auto& items : std::vector<std::vector<Item>>{
           {rgb, point}, {point, bytes, rgb}, {point, rgb, nir}, {point, point}, {point, bytes, bytes}, {}}) {
    vlr.items = items;
    EXPECT_EQ(MakeChunkDecoder(vlr).status().code(), StatusCode::kMalformed) << items.size() << " items";
  }
  vlr.items = {point, nir, wave};
  EXPECT_EQ(MakeChunkDecoder(vlr).status().code(), StatusCode::kUnsupported);
  vlr.items = {point, Item{ItemType::kRgb14, 6, 2}};
  EXPECT_EQ(MakeChunkDecoder(vlr).status().code(), StatusCode::kUnsupported);
}

// A damaged chunk may decode to other records, but only ever ends in Truncated or Malformed.
void ExpectCleanFailureOrSuccess(const Status& s) {
  EXPECT_TRUE(s.ok() || s.code() == StatusCode::kTruncated || s.code() == StatusCode::kMalformed) << s.ToString();
}

TEST(LayeredChunkHostile, EveryTruncationIsRefused) {
  SKIP_WITHOUT_LAZ_DATA();
  for (const char* name : {"laszip4j_record-format-8.laz", "pdal_1.2-with-color.copc.laz"}) {
    const FirstChunk fc = TakeFirstChunk(name);
    auto decoder = MakeDecoder(fc.file.vlr);
    ASSERT_TRUE(decoder);
    std::vector<uint8_t> out;
    for (size_t size = 0; size < fc.bytes.size(); ++size) {
      const std::vector<uint8_t> cut(fc.bytes.begin(), fc.bytes.begin() + static_cast<std::ptrdiff_t>(size));
      const Status s = DecodeChunk(*decoder, cut.data(), cut.size(), fc.points, out, fc.file.record_length);
      ASSERT_FALSE(s.ok()) << name << " cut to " << size << " bytes";
      ExpectCleanFailureOrSuccess(s);
    }
  }
}

TEST(LayeredChunkHostile, LyingCountsAndSizesAreRefused) {
  SKIP_WITHOUT_LAZ_DATA();
  const FirstChunk fc = TakeFirstChunk("laszip4j_record-format-8.laz");
  auto decoder = MakeDecoder(fc.file.vlr);
  ASSERT_TRUE(decoder);
  const uint32_t rl = fc.file.record_length;
  std::vector<uint8_t> out;
  EXPECT_EQ(DecodeChunk(*decoder, fc.bytes.data(), fc.bytes.size(), fc.points + 1, out, rl).code(),
            StatusCode::kMalformed);
  EXPECT_EQ(decoder->Start(fc.bytes.data(), fc.bytes.size(), 0).code(), StatusCode::kMalformed);
  const size_t layers = 9 + 2 + 21;
  for (size_t layer = 0; layer < layers; ++layer) {
    for (const uint32_t lie : {0xFFFFFFFFU, 0x80000000U, static_cast<uint32_t>(fc.bytes.size())}) {
      std::vector<uint8_t> bad = fc.bytes;
      std::memcpy(bad.data() + rl + 4 + 4 * layer, &lie, 4);
      EXPECT_EQ(DecodeChunk(*decoder, bad.data(), bad.size(), fc.points, out, rl).code(), StatusCode::kTruncated)
          << "layer " << layer << " of " << lie << " bytes";
    }
  }
}

// Bit flips anywhere in a chunk (first point, sizes, layers), a bounded number of cases per file.
TEST(LayeredChunkHostile, BitFlipsEndCleanly) {
  SKIP_WITHOUT_LAZ_DATA();
  std::mt19937 rng(13);
  for (const auto& [name, cases] : {std::pair{"laszip4j_record-format-8.laz", 1500},
                                    std::pair{"pdal_1.2-with-color.copc.laz", 1500},
                                    std::pair{"laszip4j_2019_saipan_waveform.laz", 150}}) {
    const FirstChunk fc = TakeFirstChunk(name);
    auto decoder = MakeDecoder(fc.file.vlr);
    ASSERT_TRUE(decoder);
    std::vector<uint8_t> out;
    size_t failed = 0;
    for (int i = 0; i < cases; ++i) {
      std::vector<uint8_t> bad = fc.bytes;
      for (int flips = 1 + static_cast<int>(rng() % 3); flips > 0; --flips) {
        bad[rng() % bad.size()] ^= static_cast<uint8_t>(1U << (rng() % 8));
      }
      const Status s = DecodeChunk(*decoder, bad.data(), bad.size(), fc.points, out, fc.file.record_length);
      ExpectCleanFailureOrSuccess(s);
      failed += s.ok() ? 0 : 1;
    }
    std::printf("%s: %zu of %d damaged chunks refused\n", name, failed, cases);
  }
}

// Decode rate of one core on the largest file (only Start + Decode are timed). Reported, not
// asserted: sanitizer and debug builds are many times slower than the Release figure in the docs.
TEST(LayeredRate, LoneStarOneCore) {
  SKIP_WITHOUT_LAZ_DATA();
  const LazFile f = OpenLaz("pdal_lone-star.copc.laz");
  auto decoder = MakeDecoder(f.vlr);
  ASSERT_TRUE(decoder);
  std::vector<uint8_t> chunk;
  double best = 0;
  for (int round = 0; round < 3; ++round) {
    const auto begin = std::chrono::steady_clock::now();
    for (const Chunk& c : f.chunks) {
      ASSERT_TRUE(DecodeChunk(*decoder, f.bytes.data() + c.start, c.size, c.points, chunk, f.record_length).ok());
    }
    const std::chrono::duration<double> seconds = std::chrono::steady_clock::now() - begin;
    best = std::max(best, static_cast<double>(f.points) / seconds.count());
  }
  std::printf("layered LAZ decode, one core: %.2f M points/s (%llu points, best of 3)\n", best / 1e6,
              static_cast<unsigned long long>(f.points));
}

}  // namespace
}  // namespace pointdag::laz
