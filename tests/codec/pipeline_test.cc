#include <gtest/gtest.h>

#include "pointdag/color/block_codec.h"
#include "pointdag/dag/dag_builder.h"
#include "pointdag/pipeline.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::DataDir;
using testing::EncodeAutzenAt4Feet;

using testing::ScanAtVoxel;

class PipelineTest : public ::testing::TestWithParam<ScanAtVoxel> {};

// voxelize -> DAG -> stored form -> container bytes -> resident -> voxels: exactly the same.
TEST_P(PipelineTest, RoundTripIsExact) {
  SKIP_WITHOUT_DATA();
  EncodeOptions options;
  options.voxel_size = GetParam().voxel;
  for (GeometryCoder coder : {GeometryCoder::kSpatial, GeometryCoder::kContext, GeometryCoder::kZstd}) {
    options.geometry_coder = coder;
    auto encoded = EncodeScan(DataDir() / GetParam().file, options);
    ASSERT_TRUE(encoded.ok()) << encoded.status().ToString();
    const auto bytes = SerializePdag(encoded->file);
    auto parsed = ParsePdag(bytes);
    ASSERT_TRUE(parsed.ok()) << parsed.status().ToString();
    auto decoded = DecodePdag(*parsed);
    ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
    EXPECT_EQ(decoded->dag, encoded->dag);
    EXPECT_EQ(decoded->grid.morton, encoded->grid.morton);
    EXPECT_EQ(decoded->grid.colors, encoded->grid.colors);
    EXPECT_EQ(decoded->grid.depth, encoded->grid.depth);
    EXPECT_EQ(decoded->grid.origin, encoded->grid.origin);  // JSON doubles round-trip exactly
    EXPECT_EQ(decoded->grid.voxel_size, encoded->grid.voxel_size);
    EXPECT_EQ(parsed->meta["voxels"], encoded->grid.morton.size());
  }
}

// Building from chunks gives the one-go DAG, and voxelizing + building chunk by chunk (bounded
// memory) writes the very same file.
TEST_P(PipelineTest, ChunkedBuildsEqualTheOneGoBuild) {
  SKIP_WITHOUT_DATA();
  EncodeOptions options;
  options.voxel_size = GetParam().voxel;
  auto whole = EncodeScan(DataDir() / GetParam().file, options);
  ASSERT_TRUE(whole.ok());
  auto chunked_dag = BuildDagChunked(whole->grid.morton, whole->grid.depth, 2);
  ASSERT_TRUE(chunked_dag.ok());
  EXPECT_EQ(*chunked_dag, whole->dag);

  options.max_points_in_memory = 100;
  auto chunked = EncodeScan(DataDir() / GetParam().file, options);
  ASSERT_TRUE(chunked.ok()) << chunked.status().ToString();
  EXPECT_GT(chunked->grid.chunk_levels, 0);
  EXPECT_EQ(SerializePdag(chunked->file), SerializePdag(whole->file));
}

INSTANTIATE_TEST_SUITE_P(SharedData, PipelineTest, ::testing::ValuesIn(testing::kEveryScan), testing::ScanFileName());

// Mipmap mode at a target: the voxels' own colors meet it (decoded from the file), and the
// reported PSNR is theirs, not that of every node's color.
TEST(Pipeline, MipmapTargetIsMetOnTheVoxels) {
  SKIP_WITHOUT_DATA();
  EncodeOptions options;
  options.voxel_size = 4.0;
  options.mipmap = true;
  options.colors = {ColorCodec::kVariableRate, 38.0};
  auto encoded = EncodeScan(DataDir() / "autzen_trim_pdrf3_rgb.las", options);
  ASSERT_TRUE(encoded.ok()) << encoded.status().ToString();
  auto decoded = DecodePdag(*ParsePdag(SerializePdag(encoded->file)));
  ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
  const ColorPsnr voxels = MeasureColorPsnr(encoded->grid.colors, decoded->grid.colors);
  EXPECT_GE(voxels.y, 38.0);
  EXPECT_LT(voxels.y, 38.5) << "the search aims at the target, not far above it";
  EXPECT_DOUBLE_EQ(encoded->colors.psnr.y, voxels.y);
}

// The target search lands just above the default target on every colored scan large enough to be
// corrected unit by unit (a macro block of voxels or more), and IGN at 0.5 m, where one unit once went
// to exact colors (38.20 dB, 28 % more bits) because a lowered threshold raised its error.
TEST(Pipeline, DefaultTargetIsMetCloselyOnEveryColoredScan) {
  SKIP_WITHOUT_DATA();
  std::vector<ScanAtVoxel> scans(std::begin(testing::kEveryScan), std::end(testing::kEveryScan));
  scans.push_back({"ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las", 0.5});
  for (const ScanAtVoxel& scan : scans) {
    EncodeOptions options;
    options.voxel_size = scan.voxel;
    options.colors = {ColorCodec::kVariableRate, 38.0};
    auto encoded = EncodeScan(DataDir() / scan.file, options);
    ASSERT_TRUE(encoded.ok()) << scan.file << ": " << encoded.status().ToString();
    if (encoded->file.meta["source"]["color_bits"] == 0 || encoded->grid.colors.size() < kMacroBlockColors) continue;
    EXPECT_GE(encoded->colors.psnr.y, 38.0) << scan.file;
    EXPECT_LT(encoded->colors.psnr.y, 38.1) << scan.file << " at " << scan.voxel;
  }
}

TEST(Pipeline, MetadataCarriesSourceCrsAndCodec) {
  SKIP_WITHOUT_DATA();
  auto encoded = EncodeAutzenAt4Feet();
  ASSERT_TRUE(encoded.ok());
  const auto& meta = encoded->file.meta;
  EXPECT_EQ(meta["source"]["format"], "LAS");
  EXPECT_EQ(meta["source"]["points"], 110000);
  EXPECT_EQ(meta["source"]["color_bits"], 8);
  EXPECT_NE(meta["crs"]["wkt"].get<std::string>().find("Lambert_Conformal_Conic"), std::string::npos);
  EXPECT_EQ(meta["crs"]["geokeys"]["keys"].size(), 21u);
  EXPECT_FALSE(meta["crs"].contains("epsg"));  // the GeoKeys say user-defined (32767)
  EXPECT_EQ(meta["codec"]["geometry"], "spatial");
  EXPECT_EQ(meta["voxels"], 36931);
  EXPECT_EQ(meta["depth"], 9);
}

// Like zstd's regression test: compressed sizes of a fixed scan at a fixed setting. When this
// fails, the change altered the format or its efficiency: update the numbers deliberately.
TEST(Pipeline, CompressedSizesAreStable) {
  SKIP_WITHOUT_DATA();
  auto encoded = EncodeAutzenAt4Feet();
  ASSERT_TRUE(encoded.ok());
  EXPECT_EQ(encoded->file.geometry.size(), 7485u);  // coder 2 v8: v5's models with young flags and lower starting weights, no level table, compact ends (7525 with v5, pattern and side models, APM, slots of heights 3 and 4; 7776 with v4, 7872 with v3, 8232 with v2, 8360 with v1, 10049 with coder 1)
  EXPECT_EQ(EncodeDag(encoded->dag, GeometryCoder::kZstd)->size(), 10408u);
  EXPECT_EQ(encoded->dag.ResidentBytes(), 33972u);
  EXPECT_EQ(SerializePdag(encoded->file).size(), 53515u);  // lossless colors v4 (columns chosen: an airborne scan), geometry coder 2 v8 (53555 with geometry v5; 54579 with lossless v3; 54830 with geometry v4; with lossless v2: 55870 with v5, 56121 with v4, 56217 with v3, 56577 with v2, 56705 with v1, 58394 with coder 1; 84872 with lossless v1)
}

TEST(Pipeline, DecodeRejectsMetadataThatContradictsTheData) {
  SKIP_WITHOUT_DATA();
  EncodeOptions options;
  options.voxel_size = 8.0;
  auto encoded = EncodeScan(DataDir() / "tiny_1.2-with-color_1065pts.las", options);
  ASSERT_TRUE(encoded.ok());
  PdagFile file = encoded->file;
  file.meta["voxels"] = file.meta["voxels"].get<uint64_t>() + 1;
  EXPECT_EQ(DecodePdag(file).status().code(), StatusCode::kCorrupt);
  file = encoded->file;
  file.meta["depth"] = 12;
  EXPECT_EQ(DecodePdag(file).status().code(), StatusCode::kCorrupt);
  file = encoded->file;
  file.meta.erase("origin");
  EXPECT_EQ(DecodePdag(file).status().code(), StatusCode::kCorrupt);
  file = encoded->file;
  file.colors.pop_back();
  EXPECT_EQ(DecodePdag(file).status().code(), StatusCode::kCorrupt);
  file = encoded->file;
  file.meta["voxels"] = "many";
  EXPECT_EQ(DecodePdag(file).status().code(), StatusCode::kCorrupt);
}

TEST(Pipeline, WaveformLazIsRefusedWithAReason) {
  const auto laz = DataDir() / "laz" / "laspy_fullwave.laz";
  if (!std::filesystem::exists(laz)) GTEST_SKIP() << laz << " not found (set POINTDAG_DATA_DIR); skipping";
  EncodeOptions options;
  options.depth = 8;
  const auto status = EncodeScan(laz, options).status();
  EXPECT_EQ(status.code(), StatusCode::kUnsupported);
  EXPECT_NE(status.message().find("WAVEPACKET14"), std::string::npos) << status.message();
}

}  // namespace
}  // namespace pointdag
