#include <gtest/gtest.h>

#include "pointdag/container/crc32c.h"
#include "pointdag/container/pdag_file.h"
#include "test_util.h"

namespace pointdag {
namespace {

PdagFile Sample() {
  PdagFile file;
  file.meta = {{"voxels", 3}, {"crs", {{"wkt", "LOCAL_CS[\"x\"]"}}}};
  file.geometry = {1, 2, 3, 4, 5, 6, 7};
  file.colors = {10, 20, 30, 40, 50, 60, 70, 80, 90};
  return file;
}

template <typename T>
void Put(std::vector<uint8_t>& b, size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof(v));
}

TEST(Crc32c, MatchesTheStandardCheckValue) {
  const std::string check = "123456789";
  EXPECT_EQ(Crc32c({reinterpret_cast<const uint8_t*>(check.data()), check.size()}), 0xE3069283u);
  EXPECT_EQ(Crc32c({}), 0u);
}

// Whichever path Crc32c takes (SSE 4.2's instruction where the CPU has it, tables elsewhere), it
// equals the bit-at-a-time definition at every length and alignment, and chains across splits.
TEST(Crc32c, EqualsTheBitwiseDefinitionAtEveryLengthAndSplit) {
  const auto bitwise = [](std::span<const uint8_t> data) {
    uint32_t c = 0xFFFFFFFFu;
    for (uint8_t byte : data) {
      c ^= byte;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0x82F63B78u & (0u - (c & 1u)));
    }
    return ~c;
  };
  std::vector<uint8_t> data(67);
  uint32_t x = 12345;
  for (uint8_t& b : data) b = static_cast<uint8_t>((x = x * 1103515245u + 12345u) >> 16);
  for (size_t start = 0; start < 9; ++start) {
    for (size_t n = 0; start + n <= data.size(); ++n) {
      const std::span<const uint8_t> part = std::span<const uint8_t>(data).subspan(start, n);
      ASSERT_EQ(Crc32c(part), bitwise(part)) << start << " " << n;
      const size_t half = n / 3;
      EXPECT_EQ(Crc32c(part.subspan(half), Crc32c(part.first(half))), bitwise(part)) << start << " " << n;
    }
  }
}

TEST(Container, RoundTrips) {
  const auto bytes = SerializePdag(Sample());
  auto file = ParsePdag(bytes);
  ASSERT_TRUE(file.ok()) << file.status().ToString();
  EXPECT_EQ(file->meta, Sample().meta);
  EXPECT_EQ(file->geometry, Sample().geometry);
  EXPECT_EQ(file->colors, Sample().colors);
  PdagFile no_color = Sample();
  no_color.colors.clear();
  EXPECT_TRUE(ParsePdag(SerializePdag(no_color))->colors.empty());
}

TEST(Container, RejectsWrongMagicAndUnknownVersion) {
  auto bytes = SerializePdag(Sample());
  bytes[0] = 'X';
  EXPECT_EQ(ParsePdag(bytes).status().code(), StatusCode::kCorrupt);
  bytes = SerializePdag(Sample());
  Put<uint16_t>(bytes, 8, 2);
  const auto status = ParsePdag(bytes).status();
  EXPECT_EQ(status.code(), StatusCode::kUnsupported);
  EXPECT_NE(status.message().find("version 2.0"), std::string::npos) << status.message();
}

TEST(Container, EveryFlippedByteIsCaught) {
  const auto good = SerializePdag(Sample());
  for (size_t i = 0; i < good.size(); ++i) {
    auto bad = good;
    bad[i] ^= 0x40;
    EXPECT_FALSE(ParsePdag(bad).ok()) << "flip at byte " << i << " went unnoticed";
  }
}

TEST(Container, BadSectionCrcNamesTheSection) {
  auto bytes = SerializePdag(Sample());
  bytes.back() ^= 1;  // last byte of the colors section
  const auto status = ParsePdag(bytes).status();
  EXPECT_EQ(status.code(), StatusCode::kCorrupt);
  EXPECT_NE(status.message().find("'colors'"), std::string::npos) << status.message();
}

TEST(Container, EveryTruncationIsCaught) {
  const auto good = SerializePdag(Sample());
  for (size_t len = 0; len < good.size(); ++len) {
    const auto status = ParsePdag(std::span(good).first(len)).status();
    EXPECT_TRUE(status.code() == StatusCode::kTruncated || status.code() == StatusCode::kCorrupt) << len;
  }
}

TEST(Container, MissingGeometryIsCorrupt) {
  // Rename the geometry section's tag and fix the header CRC: structurally valid, semantically not.
  auto bytes = SerializePdag(Sample());
  std::memcpy(bytes.data() + 32 + 32, "geomXtry", 8);
  std::vector<uint8_t> header(bytes.begin(), bytes.begin() + 32 + 3 * 32);
  std::memset(header.data() + 16, 0, 4);
  Put<uint32_t>(bytes, 16, Crc32c(header));
  const auto status = ParsePdag(bytes).status();
  EXPECT_EQ(status.code(), StatusCode::kCorrupt);
  EXPECT_NE(status.message().find("geometry"), std::string::npos);
}

TEST(Container, WritesAtomicallyAndLeavesNoTemporaryFiles) {
  testing::ScratchDir dir;
  ASSERT_TRUE(WritePdag(dir / "a.pdag", Sample()).ok());
  auto file = ReadPdag(dir / "a.pdag");
  ASSERT_TRUE(file.ok());
  EXPECT_EQ(file->geometry, Sample().geometry);
  size_t entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++entries;
  EXPECT_EQ(entries, 1u);
  EXPECT_EQ(WritePdag(dir / "no-such-dir" / "a.pdag", Sample()).code(), StatusCode::kIoError);
  EXPECT_EQ(ReadPdag(dir / "missing.pdag").status().code(), StatusCode::kIoError);
}

}  // namespace
}  // namespace pointdag
