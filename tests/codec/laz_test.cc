// LAZ and COPC against the oracle in ../shared/data/laz: every file's decompressed records hash to
// the sha256 two independent LAZ implementations agree on (manifest.json), or the file is refused
// with an Unsupported status naming what it uses; the points equal the matching LAS file's; a
// LAZ and its LAS give the same .pdag; and damaged files fail cleanly, naming the chunk.
#include <gtest/gtest.h>
#include <openssl/evp.h>

#include <nlohmann/json.hpp>

#include "pointdag/pipeline.h"
#include "pointdag/read/laz/laz_reader.h"
#include "pointdag/read/scan_reader.h"
#include "test_util.h"

namespace pointdag {
namespace {

std::filesystem::path LazDir() { return testing::DataDir() / "laz"; }

#define SKIP_WITHOUT_LAZ()                                                                              \
  do {                                                                                                  \
    if (!std::filesystem::exists(LazDir() / "manifest.json"))                                           \
      GTEST_SKIP() << "LAZ test files not found at " << LazDir() << " (set POINTDAG_DATA_DIR); skipping"; \
  } while (0)

std::string Sha256(const std::vector<uint8_t>& bytes) {
  unsigned char digest[32];
  unsigned int length = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr);
  static const char* hex = "0123456789abcdef";
  std::string s;
  for (unsigned i = 0; i < length; ++i) s += {hex[digest[i] >> 4], hex[digest[i] & 15]};
  return s;
}

// The manifest's LAZ entries (it lists the reference .las files too).
nlohmann::json Manifest() {
  std::ifstream in(LazDir() / "manifest.json");
  nlohmann::json laz = nlohmann::json::array();
  for (const auto& entry : nlohmann::json::parse(in)) {
    if (entry.contains("laszip_vlr")) laz.push_back(entry);
  }
  return laz;
}

// What we refuse, by design: LASzip 1.x's unchunked compressor and waveform items.
std::string RefusalFor(const nlohmann::json& entry) {
  const auto& vlr = entry["laszip_vlr"];
  if (vlr["compressor"] == "pointwise") return "point-wise";
  for (const auto& item : vlr["items"]) {
    if (item.get<std::string>().rfind("WAVEPACKET", 0) == 0) return "WAVEPACKET";
  }
  return "";
}

TEST(Laz, EveryManifestFileDecodesToItsHashOrIsRefusedByName) {
  SKIP_WITHOUT_LAZ();
  int decoded = 0, refused = 0;
  for (const auto& entry : Manifest()) {
    const std::string name = entry["file"];
    SCOPED_TRACE(name);
    const auto records = laz::DecodeAllRecords(LazDir() / name);
    const std::string refusal = RefusalFor(entry);
    if (!refusal.empty()) {
      ASSERT_FALSE(records.ok());
      EXPECT_EQ(records.status().code(), StatusCode::kUnsupported);
      EXPECT_NE(records.status().message().find(refusal), std::string::npos) << records.status().message();
      ++refused;
      continue;
    }
    ASSERT_TRUE(records.ok()) << records.status().ToString();
    EXPECT_EQ(records->size(), entry["points"].get<uint64_t>() * entry["record_length"].get<uint64_t>());
    EXPECT_EQ(Sha256(*records), entry["decoded_points_sha256"].get<std::string>());
    ++decoded;
  }
  EXPECT_EQ(decoded, 19);
  EXPECT_EQ(refused, 3);
}

// Through the reader every ingest uses: the same points and colors as the LAS beside the LAZ.
TEST(Laz, PointsEqualTheMatchingLasFile) {
  SKIP_WITHOUT_LAZ();
  int compared = 0;
  for (const auto& entry : Manifest()) {
    if (!entry["matches_reference_las"].is_boolean() || !entry["matches_reference_las"].get<bool>()) continue;
    if (!RefusalFor(entry).empty() || entry["points"] == 0) continue;  // the LAS reader refuses 0 points
    SCOPED_TRACE(entry["file"].get<std::string>());
    auto laz = OpenScan(LazDir() / entry["file"].get<std::string>());
    auto las = OpenScan(LazDir() / entry["reference_las"].get<std::string>());
    ASSERT_TRUE(laz.ok()) << laz.status().ToString();
    ASSERT_TRUE(las.ok()) << las.status().ToString();
    EXPECT_FALSE((*laz)->info().compression.empty());
    EXPECT_TRUE((*las)->info().compression.empty());
    EXPECT_EQ((*laz)->info().point_count, (*las)->info().point_count);
    PointBatch a, b;
    for (;;) {
      auto na = (*laz)->Read(a, 777);  // an odd batch: pieces straddle chunks
      auto nb = (*las)->Read(b, 777);
      ASSERT_TRUE(na.ok() && nb.ok());
      ASSERT_EQ(*na, *nb);
      if (*na == 0) break;
      ASSERT_EQ(a.xyz, b.xyz);
      ASSERT_EQ(a.rgb, b.rgb);
    }
    ++compared;
  }
  EXPECT_GE(compared, 10);
}

TEST(Laz, RewindReadsTheSamePointsAgain) {
  SKIP_WITHOUT_LAZ();
  auto reader = OpenScan(LazDir() / "pdal_lone-star.copc.laz");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  auto first = SurveyScan(**reader);
  auto second = SurveyScan(**reader);
  ASSERT_TRUE(first.ok() && second.ok());
  EXPECT_EQ(first->points, 518862u);
  EXPECT_EQ(first->points, second->points);
  EXPECT_EQ(first->bounds.min, second->bounds.min);
  EXPECT_EQ(first->bounds.max, second->bounds.max);
}

TEST(Laz, CopcHierarchyIsKeptAndAStaleOneIsNotTrusted) {
  SKIP_WITHOUT_LAZ();
  auto copc = OpenScan(LazDir() / "laspy_simple_with_page.copc.laz");
  ASSERT_TRUE(copc.ok()) << copc.status().ToString();
  const auto& info = (*copc)->info();
  ASSERT_TRUE(info.copc.has_value());
  EXPECT_EQ(info.copc->problem, "");
  EXPECT_EQ(info.copc->points, 1065u);
  EXPECT_EQ(info.copc->nodes.size(), 65u);  // the root page's entries and its child page's, as chunks
  EXPECT_GT(info.copc->halfsize, 0.0);
  EXPECT_NE(info.compression.find("65 variable chunks"), std::string::npos) << info.compression;

  auto stale = OpenScan(LazDir() / "laszip4j_2019_saipan_waveform.laz");
  ASSERT_TRUE(stale.ok()) << stale.status().ToString();
  ASSERT_TRUE((*stale)->info().copc.has_value());
  EXPECT_NE((*stale)->info().copc->problem.find("outside the file"), std::string::npos)
      << (*stale)->info().copc->problem;
  EXPECT_TRUE((*stale)->info().copc->nodes.empty());
  auto survey = SurveyScan(**stale);
  ASSERT_TRUE(survey.ok()) << survey.status().ToString();
  EXPECT_EQ(survey->points, 5198u);
}

TEST(Laz, AnEmptyFileDecodesToNoRecordsAndIsRefusedForIngest) {
  SKIP_WITHOUT_LAZ();
  const auto records = laz::DecodeAllRecords(LazDir() / "lazperf_no-points-1.3.laz");
  ASSERT_TRUE(records.ok()) << records.status().ToString();
  EXPECT_TRUE(records->empty());
  auto reader = OpenScan(LazDir() / "lazperf_no-points-1.3.laz");
  ASSERT_TRUE(reader.ok());
  const auto survey = SurveyScan(**reader);
  EXPECT_EQ(survey.status().code(), StatusCode::kMalformed);
}

// The same voxels: a LAZ and its decompressed LAS give the same .pdag but for the source's name.
TEST(Laz, EncodingALazGivesTheSamePdagAsItsLas) {
  SKIP_WITHOUT_LAZ();
  EncodeOptions options;
  options.voxel_size = 2.0;
  options.colors = {ColorCodec::kLossless, std::nullopt};
  const auto from_laz = EncodeScan(LazDir() / "pdal_autzen_trim.laz", options);
  const auto from_las = EncodeScan(LazDir() / "pdal_autzen_trim.las", options);
  ASSERT_TRUE(from_laz.ok()) << from_laz.status().ToString();
  ASSERT_TRUE(from_las.ok()) << from_las.status().ToString();
  EXPECT_GT(from_laz->grid.morton.size(), 1000u);
  EXPECT_EQ(from_laz->file.geometry, from_las->file.geometry);
  EXPECT_EQ(from_laz->file.colors, from_las->file.colors);
  auto laz_meta = from_laz->file.meta, las_meta = from_las->file.meta;
  EXPECT_EQ(laz_meta["source"]["name"], "pdal_autzen_trim.laz");
  laz_meta["source"].erase("name");
  las_meta["source"].erase("name");
  EXPECT_EQ(laz_meta, las_meta);  // the same metadata but for the file's name
}

// The point data of pdal_autzen_trim.laz (3 chunks of 50,000 points) with its chunk table as a
// writer that cannot seek leaves it: offset -1, and the table's offset in the last 8 bytes or not at all.
struct StreamedLaz {
  std::vector<uint8_t> bytes = testing::ReadBytes(LazDir() / "pdal_autzen_trim.laz");
  uint64_t data_offset = LoadLE<uint32_t>(bytes.data() + 96);
  uint64_t table = LoadLE<uint64_t>(bytes.data() + data_offset);

  std::vector<uint8_t> WithTrailer() const {
    auto b = bytes;
    for (int i = 0; i < 8; ++i) b[data_offset + i] = 0xFF;
    for (int i = 0; i < 8; ++i) b.push_back(static_cast<uint8_t>(table >> (8 * i)));
    return b;
  }
  std::vector<uint8_t> WithoutTable(uint64_t keep) const {
    std::vector<uint8_t> b(bytes.begin(), bytes.begin() + static_cast<long>(std::min(keep, table)));
    for (int i = 0; i < 8; ++i) b[data_offset + i] = 0xFF;
    return b;
  }
};

TEST(Laz, FilesWithoutAChunkTableAreReadChunkAfterChunk) {
  SKIP_WITHOUT_LAZ();
  testing::ScratchDir scratch;
  const StreamedLaz laz;
  const auto expected = laz::DecodeAllRecords(LazDir() / "pdal_autzen_trim.laz");
  ASSERT_TRUE(expected.ok()) << expected.status().ToString();
  testing::WriteBytes(scratch / "trailer.laz", laz.WithTrailer());
  testing::WriteBytes(scratch / "none.laz", laz.WithoutTable(laz.table));
  for (const char* name : {"trailer.laz", "none.laz"}) {
    SCOPED_TRACE(name);
    auto reader = laz::LazReader::Open(scratch / name);
    ASSERT_TRUE(reader.ok()) << reader.status().ToString();
    EXPECT_EQ((*reader)->chunks().sequential, std::string(name) == "none.laz");
    const auto records = laz::DecodeAllRecords(scratch / name);
    ASSERT_TRUE(records.ok()) << records.status().ToString();
    EXPECT_TRUE(*records == *expected);
  }
}

TEST(Laz, DamageNamesTheChunkAndAbsurdTablesAreRefusedBeforeAllocating) {
  SKIP_WITHOUT_LAZ();
  testing::ScratchDir scratch;
  const StreamedLaz laz;
  // Cut inside the second chunk of a file with its table: refused when opened.
  std::vector<uint8_t> cut(laz.bytes.begin(), laz.bytes.begin() + static_cast<long>(laz.bytes.size() * 6 / 10));
  testing::WriteBytes(scratch / "cut.laz", cut);
  auto records = laz::DecodeAllRecords(scratch / "cut.laz");
  EXPECT_EQ(records.status().code(), StatusCode::kTruncated) << records.status().ToString();
  EXPECT_NE(records.status().message().find("cut short"), std::string::npos) << records.status().message();
  // The same cut without a table: the first chunk decodes, the second runs out and says so.
  testing::WriteBytes(scratch / "streamed-cut.laz", laz.WithoutTable(laz.bytes.size() * 6 / 10));
  records = laz::DecodeAllRecords(scratch / "streamed-cut.laz");
  ASSERT_FALSE(records.ok());
  EXPECT_EQ(records.status().code(), StatusCode::kTruncated) << records.status().ToString();
  EXPECT_NE(records.status().message().find("LAZ chunk 1 of 3 (points 50000-99999"), std::string::npos)
      << records.status().message();

  // A chunk table claiming 2^32 - 1 chunks.
  auto absurd = laz.bytes;
  for (int i = 0; i < 4; ++i) absurd[laz.table + 4 + i] = 0xFF;
  testing::WriteBytes(scratch / "absurd.laz", absurd);
  records = laz::DecodeAllRecords(scratch / "absurd.laz");
  ASSERT_FALSE(records.ok());
  EXPECT_EQ(records.status().code(), StatusCode::kMalformed);
  EXPECT_NE(records.status().message().find("4294967295 chunks"), std::string::npos) << records.status().message();

  // Records that say LAZ without a LASzip VLR.
  auto flagged = testing::ReadBytes(LazDir() / "pdal_autzen_trim.las");
  flagged[104] |= 0x80;
  testing::WriteBytes(scratch / "flagged.las", flagged);
  const auto opened = OpenScan(scratch / "flagged.las");
  EXPECT_EQ(opened.status().code(), StatusCode::kMalformed);
  EXPECT_NE(opened.status().message().find("no LASzip VLR"), std::string::npos) << opened.status().message();
}

// Bit flips and truncations of a point-wise, a layered and a COPC file: each a clean status or a
// decode (a flip inside the arithmetic stream can decode to other valid records), never a crash or
// a read outside the file; the sanitizer builds run this too.
TEST(Laz, BitFlipsAndTruncationsFailCleanly) {
  SKIP_WITHOUT_LAZ();
  testing::ScratchDir scratch;
  std::mt19937 random(13);
  int failures = 0, cases = 0;
  for (const char* name : {"lazrs_extra-bytes.laz", "laszip4j_record-format-8.laz", "pdal_1.2-with-color.copc.laz"}) {
    const auto bytes = testing::ReadBytes(LazDir() / name);
    const auto path = scratch / name;
    auto attempt = [&](const std::vector<uint8_t>& damaged) {
      testing::WriteBytes(path, damaged);
      auto reader = OpenScan(path);
      ++cases;
      if (!reader.ok()) {
        ++failures;
        return;
      }
      PointBatch batch;
      for (;;) {
        auto n = (*reader)->Read(batch, 500);
        if (!n.ok()) {
          ++failures;
          break;
        }
        if (*n == 0) break;
      }
    };
    for (size_t length = 0; length < bytes.size(); length += 1 + bytes.size() / 300) {
      attempt(std::vector<uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(length)));
    }
    for (int flip = 0; flip < 800; ++flip) {
      auto damaged = bytes;
      const size_t at = std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(random);
      damaged[at] ^= static_cast<uint8_t>(1u << (flip % 8));
      attempt(damaged);
    }
  }
  EXPECT_GE(cases, 3000);
  EXPECT_GT(failures, 900);  // every truncation fails
}

}  // namespace
}  // namespace pointdag
