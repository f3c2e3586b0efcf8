// The point-wise chunk decoder (POINT10, GPSTIME11, RGB12, BYTE v2) on the public LAZ files of
// ../shared/data/laz, chunk by chunk (laz_test checks whole files against the manifest's sha256):
// the records equal the matching LAS file's, whatever the batch size; each chunk's BytesUsed() is
// its size in the chunk table (how files without a table are read); damaged chunks fail cleanly.
#include <gtest/gtest.h>

#include <cctype>
#include <cstring>
#include <string>
#include <vector>

#include "pointdag/read/laz/laz_reader.h"
#include "pointdag/read/laz/pointwise_chunk_decoder.h"
#include "test_util.h"

namespace pointdag::laz {
namespace {

using testing::DataDir;
using testing::ReadBytes;

// A LAZ file's bytes with its VLR and chunk table, as the reader finds them.
struct LazFile {
  std::vector<uint8_t> bytes;
  LaszipVlr vlr;
  ChunkTable chunks;
  size_t record_length = 0;
  uint64_t points = 0;
};

LazFile OpenLaz(const std::string& name) {
  LazFile f;
  auto reader = LazReader::Open(DataDir() / "laz" / name);
  EXPECT_TRUE(reader.ok()) << reader.status().ToString();
  if (!reader.ok()) return f;
  f.bytes = ReadBytes(DataDir() / "laz" / name);
  f.vlr = (*reader)->vlr();
  f.chunks = (*reader)->chunks();
  f.record_length = (*reader)->record_length();
  for (uint64_t n : f.chunks.points) f.points += n;
  return f;
}

// Decodes every chunk straight from the table's bounds, `batch` points per Decode() call, and
// checks that each chunk's BytesUsed() is its whole size (what files without a table rely on).
std::vector<uint8_t> DecodeChunks(const LazFile& f, size_t batch) {
  auto decoder = MakePointwiseChunkDecoder(f.vlr);
  EXPECT_TRUE(decoder.ok()) << decoder.status().ToString();
  if (!decoder.ok()) return {};
  std::vector<uint8_t> records(f.points * f.record_length);
  uint8_t* out = records.data();
  for (size_t c = 0; c < f.chunks.size(); ++c) {
    const size_t size = f.chunks.starts[c + 1] - f.chunks.starts[c];
    EXPECT_TRUE((*decoder)->Start(f.bytes.data() + f.chunks.starts[c], size, f.chunks.points[c]).ok());
    for (uint64_t left = f.chunks.points[c]; left > 0;) {
      const size_t n = std::min<uint64_t>(batch, left);
      const Status s = (*decoder)->Decode(out, n);
      EXPECT_TRUE(s.ok()) << "chunk " << c << ": " << s.ToString();
      if (!s.ok()) return {};
      out += n * f.record_length;
      left -= n;
    }
    EXPECT_EQ((*decoder)->BytesUsed(), size) << "chunk " << c;
  }
  return records;
}

// The point records of a LAS file.
std::vector<uint8_t> LasRecords(const std::string& name) {
  const std::vector<uint8_t> las = ReadBytes(DataDir() / "laz" / name);
  const size_t offset = LoadLE<uint32_t>(las.data() + 96);
  const size_t length = LoadLE<uint16_t>(las.data() + 105) * size_t{LoadLE<uint32_t>(las.data() + 107)};
  return {las.begin() + static_cast<ptrdiff_t>(offset), las.begin() + static_cast<ptrdiff_t>(offset + length)};
}

#define SKIP_WITHOUT_LAZ()                                                                 \
  do {                                                                                     \
    if (!std::filesystem::exists(DataDir() / "laz" / "manifest.json"))                     \
      GTEST_SKIP() << "LAZ files not found at " << DataDir() / "laz" << "; skipping";      \
  } while (0)

// A point-wise file and the LAS file its records equal (nullptr: none beside it; the manifest's
// sha256 for those is laz_test's).
struct Pair {
  const char* laz;
  const char* las;
};

class LazPointwiseFiles : public ::testing::TestWithParam<Pair> {};

TEST_P(LazPointwiseFiles, ChunksDecodeToTheLasRecordsAndEndAtTheirSize) {
  SKIP_WITHOUT_LAZ();
  const LazFile f = OpenLaz(GetParam().laz);
  ASSERT_GT(f.points, 0U);
  const std::vector<uint8_t> records = DecodeChunks(f, 4096);
  ASSERT_EQ(records.size(), f.points * f.record_length);
  EXPECT_EQ(DecodeChunks(f, 1), records);  // one point per call decodes the same
  if (GetParam().las == nullptr) return;
  const std::vector<uint8_t> expected = LasRecords(GetParam().las);
  ASSERT_EQ(expected.size(), records.size());
  for (size_t i = 0; i < f.points; ++i) {
    ASSERT_EQ(0, std::memcmp(records.data() + i * f.record_length, expected.data() + i * f.record_length,
                             f.record_length))
        << "point " << i << " differs";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Files, LazPointwiseFiles,
    ::testing::Values(Pair{"lazrs_point10.laz", "lazrs_point10.las"},
                      Pair{"lazrs_point-time.laz", "lazrs_point-time.las"},
                      Pair{"lazrs_point-color.laz", "lazrs_point-color.las"},
                      Pair{"lazrs_point-time-color.laz", "lazrs_point-time-color.las"},
                      Pair{"lazrs_extra-bytes.laz", "lazrs_extra-bytes.las"},  // 27 extra bytes
                      Pair{"pdal_simple.laz", "pdal_simple.las"},
                      Pair{"pdal_autzen_trim.laz", "pdal_autzen_trim.las"},  // 3 chunks
                      Pair{"lazperf_point-time-1.4.laz", "lazrs_point-time.las"},
                      Pair{"lazperf_point10-1.0.laz", "lazperf_point10-1.0.las"},  // 1 point
                      Pair{"pdal_lone-star.laz", nullptr}),                      // 11 chunks
    [](const auto& param_info) {
      std::string name = param_info.param.laz;
      for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
      return name;
    });

// A chunk of one point: the raw point, then the 4 bytes LASzip's encoder ends every stream with.
TEST(LazPointwise, OnePointChunkIsItsRawPointAndFourStreamBytes) {
  SKIP_WITHOUT_LAZ();
  const LazFile f = OpenLaz("lazperf_point10-1.0.laz");
  ASSERT_EQ(f.chunks.size(), 1U);
  EXPECT_EQ(f.chunks.starts[1] - f.chunks.starts[0], f.record_length + 4);
  DecodeChunks(f, 1);
}

// Every way the chunk of pdal_simple.laz (PDRF 3) can end early, and flipped bits: a clean status
// or some records, never a read outside the chunk (the sanitizer builds check that).
TEST(LazPointwise, TruncatedAndFlippedChunksFailCleanly) {
  SKIP_WITHOUT_LAZ();
  const LazFile f = OpenLaz("pdal_simple.laz");
  ASSERT_EQ(f.chunks.size(), 1U);
  auto decoder = MakePointwiseChunkDecoder(f.vlr);
  ASSERT_TRUE(decoder.ok());
  const std::vector<uint8_t> original(f.bytes.begin() + static_cast<ptrdiff_t>(f.chunks.starts[0]),
                                      f.bytes.begin() + static_cast<ptrdiff_t>(f.chunks.starts[1]));
  std::vector<uint8_t> records(f.points * f.record_length);
  for (size_t size = 0; size < original.size(); size += 1 + size / 16) {
    // A copy of exactly `size` bytes, so that ASan sees a read past it.
    const std::vector<uint8_t> cut(original.begin(), original.begin() + static_cast<ptrdiff_t>(size));
    const Status start = (*decoder)->Start(cut.data(), cut.size(), f.points);
    if (!start.ok()) {
      EXPECT_EQ(start.code(), StatusCode::kTruncated);
      continue;
    }
    EXPECT_EQ((*decoder)->Decode(records.data(), f.points).code(), StatusCode::kTruncated) << size << " bytes";
  }
  std::mt19937 rng(13);
  for (int i = 0; i < 300; ++i) {
    std::vector<uint8_t> flipped = original;
    flipped[rng() % flipped.size()] ^= static_cast<uint8_t>(1U << (rng() % 8));
    ASSERT_TRUE((*decoder)->Start(flipped.data(), flipped.size(), f.points).ok());
    const Status s = (*decoder)->Decode(records.data(), f.points);
    EXPECT_TRUE(s.ok() || s.code() == StatusCode::kTruncated || s.code() == StatusCode::kMalformed) << s.ToString();
  }
}

TEST(LazPointwise, RefusesItemListsLaszipDoesNotWrite) {
  LaszipVlr vlr;
  vlr.compressor = Compressor::kPointwiseChunked;
  vlr.chunk_size = 50000;
  vlr.items = {{ItemType::kPoint10, 20, 2}, {ItemType::kRgb12, 6, 2}, {ItemType::kRgb12, 6, 2}};
  EXPECT_EQ(MakePointwiseChunkDecoder(vlr).status().code(), StatusCode::kUnsupported);
  vlr.items = {{ItemType::kPoint10, 20, 2}, {ItemType::kByte, 2000, 2}};
  EXPECT_EQ(MakePointwiseChunkDecoder(vlr).status().code(), StatusCode::kResourceLimit);
  vlr.items = {{ItemType::kPoint10, 20, 2}, {ItemType::kByte, 3, 2}};
  auto decoder = MakePointwiseChunkDecoder(vlr);
  ASSERT_TRUE(decoder.ok());
  // More points than the chunk was started with is a caller's bug, not a crash.
  const uint8_t bytes[23] = {};
  ASSERT_TRUE((*decoder)->Start(bytes, sizeof(bytes), 1).ok());
  uint8_t out[46];
  EXPECT_EQ((*decoder)->Decode(out, 2).code(), StatusCode::kInternal);
}

}  // namespace
}  // namespace pointdag::laz
