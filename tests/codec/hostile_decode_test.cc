// Hostile input for the decoders behind `pointdag info/decode` and `pointdag fetch`: every case is
// a finding of issue 11 (or of fuzzing), and each is refused with a typed status before it can
// allocate by what it declares, overflow the stack or throw.
#include <zstd.h>

#include "hostile_pdag.h"
#include "pointdag/color/astc_mapping.h"
#include "pointdag/color/block_codec.h"
#include "pointdag/color/color_codec.h"
#include "pointdag/entropy/varint.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::DataDir;

StatusOr<DecodedPdag> DecodeBytes(const std::vector<uint8_t>& bytes, const DecodeLimits& limits = {}) {
  ASSIGN_OR_RETURN(const PdagFile file, ParsePdag(bytes));
  return DecodePdag(file, limits);
}

bool Mentions(const Status& status, const std::string& fragment) {
  return status.message().find(fragment) != std::string::npos;
}

TEST(HostilePdag, DenseCubeOfABillionVoxelsIsRefusedBeforeItsVoxelsAreEnumerated) {
  const auto geometry = EncodeDag(testing::DenseCube(10), GeometryCoder::kContext).value();
  PdagFile file;
  file.meta = testing::MinimalMeta(uint64_t{1} << 30, 10);
  file.geometry = geometry;
  const auto bytes = SerializePdag(file);
  EXPECT_LT(bytes.size(), 300u);  // a few hundred bytes that would enumerate 8 GB of Morton codes
  const Status status = DecodeBytes(bytes).status();
  EXPECT_EQ(status.code(), StatusCode::kResourceLimit) << status.ToString();
  EXPECT_TRUE(Mentions(status, "this decoder allows")) << status.ToString();
  // Within a caller's larger limit the same cube (depth 4, 4096 voxels) decodes.
  file.meta = testing::MinimalMeta(4096, 4);
  file.geometry = EncodeDag(testing::DenseCube(4), GeometryCoder::kZstd).value();
  const auto small = DecodeBytes(SerializePdag(file));
  ASSERT_TRUE(small.ok()) << small.status().ToString();
  EXPECT_EQ(small->grid.morton.size(), 4096u);
}

TEST(HostilePdag, DeclaredVoxelCountAboveTheLimitIsAResourceLimit) {
  SKIP_WITHOUT_DATA();
  EncodeOptions options;
  options.voxel_size = 40.0;
  auto encoded = EncodeScan(DataDir() / "tiny_1.2-with-color_1065pts.las", options);
  ASSERT_TRUE(encoded.ok());
  PdagFile file = encoded->file;
  file.meta["voxels"] = uint64_t{1} << 40;
  const Status status = DecodeBytes(SerializePdag(file)).status();
  EXPECT_EQ(status.code(), StatusCode::kResourceLimit) << status.ToString();
  DecodeLimits tight;
  tight.max_voxels = 10;  // the caller's own bound holds against a true count too
  EXPECT_EQ(DecodeBytes(SerializePdag(encoded->file), tight).status().code(), StatusCode::kResourceLimit);
}

TEST(HostilePdag, WronglyTypedMetadataIsCorruptNotAnException) {
  const auto geometry = EncodeDag(testing::DenseCube(4), GeometryCoder::kContext).value();
  const std::pair<const char*, nlohmann::json> cases[] = {
      {"source", {{"points", "many"}}},  // .value() threw type_error here
      {"source", 5},
      {"depth", 4.5},
      {"depth", "4"},
      {"voxels", -1},
      {"voxel_size", nullptr},
      {"origin", {1.0, "x", 2.0}},
  };
  for (const auto& [key, value] : cases) {
    PdagFile file;
    file.meta = testing::MinimalMeta(4096, 4);
    file.meta[key] = value;
    file.geometry = geometry;
    StatusOr<DecodedPdag> decoded = Internal("not run");
    EXPECT_NO_THROW(decoded = DecodeBytes(SerializePdag(file))) << key;
    EXPECT_EQ(decoded.status().code(), StatusCode::kCorrupt) << key << " = " << value.dump();
    EXPECT_TRUE(Mentions(decoded.status(), key)) << decoded.status().ToString();
  }
}

TEST(HostilePdag, DeeplyNestedMetadataIsRefusedWithoutRecursion) {
  const auto geometry = EncodeDag(testing::DenseCube(4), GeometryCoder::kContext).value();
  const std::string nested = "{\"a\":" + std::string(300000, '[') + std::string(300000, ']') + "}";
  const Status status = ParsePdag(testing::RewrapPdag(nested, geometry)).status();
  EXPECT_EQ(status.code(), StatusCode::kCorrupt);
  EXPECT_TRUE(Mentions(status, "nested deeper")) << status.ToString();
  // The same framing with honest metadata parses: the test's container is sound.
  EXPECT_TRUE(ParsePdag(testing::RewrapPdag(testing::MinimalMeta(4096, 4).dump(), geometry)).ok());
}

// ---- The stored DAG stream ----

TEST(HostileDagStream, ContextCodedLevelTableLargerThanItsBytesCanHoldIsRefused) {
  std::vector<uint8_t> bytes = {1, 1, 7, 0};
  for (uint64_t c : {1, 8, 64, 512, 4096, 32768}) PutVarint(bytes, c);
  bytes.insert(bytes.end(), {0xFF, 0xFF});
  const Status status = DecodeDag(bytes).status();
  EXPECT_EQ(status.code(), StatusCode::kCorrupt);
  EXPECT_TRUE(Mentions(status, "bytes can hold")) << status.ToString();
}

std::vector<uint8_t> Zstd(const std::vector<uint8_t>& data) {
  std::vector<uint8_t> out(ZSTD_compressBound(data.size()));
  out.resize(ZSTD_compress(out.data(), out.size(), data.data(), data.size(), 3));
  return out;
}

TEST(HostileDagStream, ZstdStreamsAreBoundedByTheCountsNotByTheirFrames) {
  // Depth 4: one root, one level-1 node, one brick. Its masks can need at most 1 + 1 + 9 bytes.
  std::vector<uint8_t> bytes = {1, 0, 4, 0, 1, 1, 1};
  const auto masks = Zstd(std::vector<uint8_t>(1 << 20, 0x01)), flags = Zstd({0}), refs = Zstd({0});
  for (const auto* s : {&masks, &flags, &refs}) PutVarint(bytes, s->size());
  for (const auto* s : {&masks, &flags, &refs}) bytes.insert(bytes.end(), s->begin(), s->end());
  const Status status = DecodeDag(bytes).status();
  EXPECT_EQ(status.code(), StatusCode::kCorrupt);
  EXPECT_TRUE(Mentions(status, "its counts allow")) << status.ToString();
}

// ---- Color sections: the count comes from decoded geometry; the bytes must still hold it ----

TEST(HostileColors, LosslessFrameDeclaringGigabytesIsNotAllocatedByItsHeader) {
  // A zstd frame whose header declares 3 * 2^31 bytes and which holds one.
  const uint64_t count = uint64_t{1} << 31;
  std::vector<uint8_t> section = {static_cast<uint8_t>(ColorCodec::kLossless), 0x28, 0xB5, 0x2F, 0xFD, 0xE0};
  for (int i = 0; i < 8; ++i) section.push_back(static_cast<uint8_t>((3 * count) >> (8 * i)));
  section.insert(section.end(), {0x09, 0x00, 0x00, 0x42});  // last block, raw, 1 byte
  const Status status = DecodeColors(section, count).status();
  EXPECT_EQ(status.code(), StatusCode::kCorrupt) << status.ToString();
}

TEST(HostileColors, BlockStreamDeclaringMoreColorsThanItsBytesHoldIsRefused) {
  const uint64_t count = uint64_t{1} << 31;
  std::vector<uint8_t> section = {static_cast<uint8_t>(ColorCodec::kVariableRate), 1, 2, 0, 0};
  PutVarint(section, count);
  PutVarint(section, 1);
  PutVarint(section, 4);
  section.insert(section.end(), {0, 0, 0, 0});
  const Status status = DecodeColors(section, count).status();
  EXPECT_EQ(status.code(), StatusCode::kCorrupt);
  EXPECT_TRUE(Mentions(status, "bytes can hold")) << status.ToString();
}

TEST(HostileColors, HugeCountsAreRefusedNotLoopedOn) {
  // TextureSide() looped forever on counts above 2^62 (its side wrapped to 0).
  const std::vector<uint8_t> image = {static_cast<uint8_t>(ColorCodec::kPng), 0, 0, 1, 0x89, 'P', 'N', 'G'};
  EXPECT_EQ(DecodeColors(image, uint64_t{1} << 63).status().code(), StatusCode::kResourceLimit);
  EXPECT_EQ(DecodeColorImage(std::span(image).subspan(1), uint64_t{1} << 63).status().code(), StatusCode::kCorrupt);
  const std::vector<uint8_t> astc = {1, 12, 0x80, 0x80, 0x04};  // side 65536, no blocks
  EXPECT_EQ(DecodeColorAstc(astc, uint64_t{1} << 32).status().code(), StatusCode::kCorrupt);
  EXPECT_EQ(DecodeColors(std::vector<uint8_t>{0, 1, 2, 3}, uint64_t{1} << 62).status().code(), StatusCode::kResourceLimit);
}

TEST(HostileColors, ImageOfAnotherFormatOrCutShortIsCorrupt) {
  std::vector<Rgb8> colors(300);
  for (size_t i = 0; i < colors.size(); ++i) colors[i] = {static_cast<uint8_t>(i), 90, static_cast<uint8_t>(255 - i)};
  auto jpeg = EncodeColorImage(colors, Curve::kHilbert, ImageFormat::kJpeg, 90);
  ASSERT_TRUE(jpeg.ok());
  ASSERT_TRUE(DecodeColorImage(*jpeg, colors.size()).ok());
  (*jpeg)[1] = static_cast<uint8_t>(ImageFormat::kPng);  // a JPEG labelled PNG: refused before libpng sees it
  const Status status = DecodeColorImage(*jpeg, colors.size()).status();
  EXPECT_EQ(status.code(), StatusCode::kCorrupt);
  EXPECT_TRUE(Mentions(status, "not a png file")) << status.ToString();
  // Each format's library says "cut short" as an error, never as a warning with texels made up.
  for (ImageFormat format : {ImageFormat::kPng, ImageFormat::kJpeg, ImageFormat::kWebp}) {
    auto image = EncodeColorImage(colors, Curve::kHilbert, format, 90);
    ASSERT_TRUE(image.ok());
    image->resize(image->size() / 2);
    EXPECT_EQ(DecodeColorImage(*image, colors.size()).status().code(), StatusCode::kCorrupt) << ImageFormatName(format);
  }
}

}  // namespace
}  // namespace pointdag
