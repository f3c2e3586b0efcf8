// The point-wise chunk decoder (POINT10, GPSTIME11, RGB12, BYTE v2) on the public LAZ files of
// ../shared/data/laz: every chunk decodes to the matching LAS file's record bytes, chunk after chunk
// ends exactly where the next (or the chunk table) starts, and damaged chunks fail cleanly.
#include <gtest/gtest.h>

#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "pointdag/read/laz/chunk_decoder.h"
#include "pointdag/read/laz/laszip_vlr.h"
#include "pointdag/read/laz/pointwise_chunk_decoder.h"
#include "test_util.h"

namespace pointdag::laz {
namespace {

using testing::DataDir;
using testing::ReadBytes;

// Just enough of a LAS/LAZ header to find the points and the LASzip VLR (the reader does it properly).
struct LazFile {
  std::vector<uint8_t> bytes;
  size_t point_data = 0;   // offset_to_point_data
  size_t record_length = 0;
  uint64_t points = 0;
  size_t chunk_table = 0;  // where the chunks end
  LaszipVlr vlr;
};

LazFile OpenLaz(const std::string& name) {
  LazFile f;
  f.bytes = ReadBytes(DataDir() / "laz" / name);
  const uint8_t* b = f.bytes.data();
  f.point_data = LoadLE<uint32_t>(b + 96);
  f.record_length = LoadLE<uint16_t>(b + 105);
  f.points = LoadLE<uint32_t>(b + 107);
  if (b[25] >= 4 && f.points == 0) f.points = LoadLE<uint64_t>(b + 247);
  f.chunk_table = static_cast<size_t>(LoadLE<int64_t>(b + f.point_data));
  size_t at = LoadLE<uint16_t>(b + 94);  // header size: the VLRs follow
  for (uint32_t i = 0, n = LoadLE<uint32_t>(b + 100); i < n; ++i) {
    const size_t length = LoadLE<uint16_t>(b + at + 20);
    if (FixedString(b + at + 2, 16) == "laszip encoded" && LoadLE<uint16_t>(b + at + 18) == 22204) {
      auto vlr = ParseLaszipVlr(std::vector<unsigned char>(b + at + 54, b + at + 54 + length),
                                static_cast<uint32_t>(f.record_length));
      EXPECT_TRUE(vlr.ok()) << vlr.status().ToString();
      if (vlr.ok()) f.vlr = *vlr;
    }
    at += 54 + length;
  }
  return f;
}

// Decodes every chunk, each starting where the previous one's BytesUsed() ends; checks that the
// last one ends at the chunk table. Points come in batches of `batch` to exercise Decode's resumption.
std::vector<uint8_t> DecodeChunks(const LazFile& f, size_t batch = 4096) {
  auto decoder = MakePointwiseChunkDecoder(f.vlr);
  EXPECT_TRUE(decoder.ok()) << decoder.status().ToString();
  if (!decoder.ok()) return {};
  std::vector<uint8_t> records(f.points * f.record_length);
  size_t at = f.point_data + 8;
  for (uint64_t done = 0; done < f.points;) {
    const uint64_t points = std::min<uint64_t>(f.vlr.chunk_size, f.points - done);
    EXPECT_TRUE((*decoder)->Start(f.bytes.data() + at, f.chunk_table - at, points).ok());
    for (uint64_t i = 0; i < points;) {
      const size_t n = std::min<uint64_t>(batch, points - i);
      const Status s = (*decoder)->Decode(records.data() + (done + i) * f.record_length, n);
      EXPECT_TRUE(s.ok()) << "chunk at " << at << ": " << s.ToString();
      if (!s.ok()) return {};
      i += n;
    }
    at += (*decoder)->BytesUsed();
    done += points;
  }
  EXPECT_EQ(at, f.chunk_table) << "the chunks do not end at the chunk table";
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

struct Pair {
  const char* laz;
  const char* las;
};

class LazPointwiseMatchesLas : public ::testing::TestWithParam<Pair> {};

TEST_P(LazPointwiseMatchesLas, RecordsEqualTheLasFile) {
  SKIP_WITHOUT_LAZ();
  const LazFile f = OpenLaz(GetParam().laz);
  const std::vector<uint8_t> expected = LasRecords(GetParam().las);
  ASSERT_EQ(expected.size(), f.points * f.record_length);
  const std::vector<uint8_t> records = DecodeChunks(f);
  ASSERT_EQ(records.size(), expected.size());
  for (size_t i = 0; i < f.points; ++i) {
    ASSERT_EQ(0, std::memcmp(records.data() + i * f.record_length, expected.data() + i * f.record_length,
                             f.record_length))
        << "point " << i << " differs";
  }
  // One point at a time decodes the same.
  EXPECT_EQ(DecodeChunks(f, 1), records);
}

INSTANTIATE_TEST_SUITE_P(
    Files, LazPointwiseMatchesLas,
    ::testing::Values(Pair{"lazrs_point10.laz", "lazrs_point10.las"},
                      Pair{"lazrs_point-time.laz", "lazrs_point-time.las"},
                      Pair{"lazrs_point-color.laz", "lazrs_point-color.las"},
                      Pair{"lazrs_point-time-color.laz", "lazrs_point-time-color.las"},
                      Pair{"lazrs_extra-bytes.laz", "lazrs_extra-bytes.las"},
                      Pair{"pdal_simple.laz", "pdal_simple.las"},
                      Pair{"pdal_autzen_trim.laz", "pdal_autzen_trim.las"},  // 3 chunks
                      Pair{"lazperf_point-time-1.4.laz", "lazrs_point-time.las"},
                      Pair{"lazperf_point10-1.0.laz", "lazperf_point10-1.0.las"}),  // 1 point
    [](const auto& param_info) {
      std::string name = param_info.param.laz;
      for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
      return name;
    });

TEST(LazPointwise, OnePointChunkIsItsRawPointAndFourStreamBytes) {
  SKIP_WITHOUT_LAZ();
  const LazFile f = OpenLaz("lazperf_point10-1.0.laz");
  auto decoder = MakePointwiseChunkDecoder(f.vlr);
  ASSERT_TRUE(decoder.ok());
  std::vector<uint8_t> record(f.record_length);
  ASSERT_TRUE((*decoder)->Start(f.bytes.data() + f.point_data + 8, f.chunk_table - f.point_data - 8, 1).ok());
  ASSERT_TRUE((*decoder)->Decode(record.data(), 1).ok());
  EXPECT_EQ((*decoder)->BytesUsed(), f.record_length + 4);
}

// 518,862 points of PDRF 1 in 11 chunks, with no LAS beside it: a digest of the records, taken when
// `sha256sum` of them matched the manifest's decoded_points_sha256.
TEST(LazPointwise, LoneStarElevenChunks) {
  SKIP_WITHOUT_LAZ();
  const LazFile f = OpenLaz("pdal_lone-star.laz");
  ASSERT_EQ(f.points, 518862U);
  const auto start = std::chrono::steady_clock::now();
  const std::vector<uint8_t> records = DecodeChunks(f);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(records.size(), f.points * f.record_length);
  uint64_t fnv = 0xcbf29ce484222325ULL;  // FNV-1a
  for (uint8_t b : records) fnv = (fnv ^ b) * 0x100000001b3ULL;
  EXPECT_EQ(fnv, 0xeb88d8fe91dcc301ULL);
  std::printf("decoded %llu points in %.3f s: %.2f M points/s\n", static_cast<unsigned long long>(f.points), seconds,
              static_cast<double>(f.points) / seconds / 1e6);
}

// Every way a chunk of pdal_simple.laz (PDRF 3) can end early, and flipped bits: a clean status or
// some records, never a read outside the chunk (the sanitizer builds check that).
TEST(LazPointwise, TruncatedAndFlippedChunksFailCleanly) {
  SKIP_WITHOUT_LAZ();
  const LazFile f = OpenLaz("pdal_simple.laz");
  auto decoder = MakePointwiseChunkDecoder(f.vlr);
  ASSERT_TRUE(decoder.ok());
  const size_t chunk = f.chunk_table - f.point_data - 8;
  const std::vector<uint8_t> original(f.bytes.begin() + static_cast<ptrdiff_t>(f.point_data + 8),
                                      f.bytes.begin() + static_cast<ptrdiff_t>(f.chunk_table));
  std::vector<uint8_t> records(f.points * f.record_length);
  for (size_t size = 0; size < chunk; size += 1 + size / 16) {
    std::vector<uint8_t> cut(original.begin(), original.begin() + static_cast<ptrdiff_t>(size));  // ASan sees the end
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
