// Hostile scans. PLY and PCD files: each is refused by our own header check (read/ply_pcd_header.h)
// with a typed status before PCL sees it, or read without PCL over-allocating or reading out of
// bounds. LAS text records that are not UTF-8: encoded, with valid UTF-8 in the metadata.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "pointdag/container/pdag_file.h"
#include "pointdag/json_text.h"
#include "pointdag/pipeline.h"
#include "pointdag/read/scan_reader.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::LasSpec;
using testing::MakeLas;
using testing::ScratchDir;
using testing::WriteBytes;

void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Opens `text` as a file named `name` and expects `code` with `fragment` in the message.
void ExpectRefused(const std::string& name, const std::string& text, StatusCode code, const std::string& fragment) {
  SCOPED_TRACE(fragment);
  ScratchDir dir;
  WriteText(dir / name, text);
  const auto reader = OpenScan(dir / name);
  ASSERT_FALSE(reader.ok()) << name << " was accepted";
  EXPECT_EQ(reader.status().code(), code) << reader.status().ToString();
  EXPECT_NE(reader.status().message().find(fragment), std::string::npos) << reader.status().message();
}

std::string Floats(std::initializer_list<float> values) {
  std::string bytes;
  for (float v : values) bytes.append(reinterpret_cast<const char*>(&v), 4);
  return bytes;
}

const std::string kXyzPlyProps = "property float x\nproperty float y\nproperty float z\n";

// ---- the cases from issue 11 ----

// `# .PCD v0.7\n` segfaulted inside PCL (the daemon died on a 12-byte upload).
TEST(HostilePcd, TwelveByteCommentOnlyPcd) {
  const std::string bytes = "# .PCD v0.7\n";
  ASSERT_EQ(bytes.size(), 12u);
  ExpectRefused("twelve.pcd", bytes, StatusCode::kMalformed, "PCD file ends before its header's DATA line");
}

TEST(HostilePcd, TwelveByteFileMakesTheCliExitOneWithTheReason) {
  ScratchDir dir;
  WriteText(dir / "twelve.pcd", "# .PCD v0.7\n");
  const std::string command = std::string(POINTDAG_CLI) + " encode " + (dir / "twelve.pcd").string() + " -o " +
                              (dir / "out.pdag").string() + " --voxel 1 2>" + (dir / "err.txt").string();
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status)) << "the CLI died of a signal";
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const auto err = testing::ReadBytes(dir / "err.txt");
  EXPECT_NE(std::string(err.begin(), err.end()).find("Malformed: PCD file ends before its header's DATA line"),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "out.pdag"));
}

// 135 bytes declaring 3e8 vertices took the daemon to 3.6 GB before anything was read.
TEST(HostilePly, TinyBinaryPlyDeclaringThreeHundredMillionVertices) {
  const std::string bytes = "ply\nformat binary_little_endian 1.0\nelement vertex 300000000\n" + kXyzPlyProps +
                            "end_header\n" + Floats({1, 2, 3});
  ASSERT_EQ(bytes.size(), 135u);
  ExpectRefused("big.ply", bytes, StatusCode::kTruncated,
                "PLY header declares 300000000 points of 12 bytes but the file holds only 1 complete records");
}

TEST(HostilePly, AsciiPlyDeclaringMoreVerticesThanItsTextCanHold) {
  ExpectRefused("big.ply", "ply\nformat ascii 1.0\nelement vertex 300000000\n" + kXyzPlyProps + "end_header\n1 2 3\n",
                StatusCode::kTruncated, "300000000 points of 3 values but the 6 bytes of ASCII data left can hold at most 1");
}

// COUNT 1e9 on a field took the daemon to 4.1 GB.
TEST(HostilePcd, FieldCountOfABillion) {
  ExpectRefused("count.pcd",
                "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1000000000 1 1\nWIDTH 1\nHEIGHT 1\n"
                "POINTS 1\nDATA ascii\n1 2 3\n",
                StatusCode::kResourceLimit, "COUNT 1000000000 of field 'x' is more than the 65536 allowed");
  ExpectRefused("count.pcd",
                "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1e9 1 1\nWIDTH 1\nHEIGHT 1\n"
                "POINTS 1\nDATA ascii\n1 2 3\n",
                StatusCode::kMalformed, "COUNT '1e9' is not a non-negative integer");
}

// ---- PCD: counts bounded by the bytes after the header ----

const std::string kXyzPcd = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

TEST(HostilePcd, BinaryPointsBeyondTheFile) {
  ExpectRefused("cut.pcd", kXyzPcd + "WIDTH 100\nHEIGHT 1\nPOINTS 100\nDATA binary\n" + std::string(40, '\0'),
                StatusCode::kTruncated, "PCD header declares 100 points of 12 bytes but the file holds only 3 complete records");
}

TEST(HostilePcd, AsciiPointsBeyondTheFile) {
  ExpectRefused("cut.pcd", kXyzPcd + "WIDTH 4000000000\nHEIGHT 1\nPOINTS 4000000000\nDATA ascii\n1 2 3\n",
                StatusCode::kTruncated, "4000000000 points of 3 values but its 6 bytes of ASCII data can hold at most 1");
}

TEST(HostilePcd, PointsBeyondThirtyTwoBits) {
  ExpectRefused("huge.pcd", kXyzPcd + "WIDTH 5000000000\nHEIGHT 1\nPOINTS 5000000000\nDATA ascii\n1 2 3\n",
                StatusCode::kResourceLimit, "WIDTH 5000000000 is more than the 4294967295 allowed");
}

TEST(HostilePcd, WidthTimesHeightIsNotPoints) {
  ExpectRefused("wh.pcd", kXyzPcd + "WIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n1 2 3\n1 2 3\n1 2 3\n",
                StatusCode::kMalformed, "WIDTH × HEIGHT (2 × 2) is not POINTS (3)");
}

// Two little-endian uint32 size words, then the payload.
std::string Compressed(uint32_t compressed, uint32_t uncompressed, const std::string& payload) {
  std::string bytes(8, '\0');
  std::memcpy(bytes.data(), &compressed, 4);
  std::memcpy(bytes.data() + 4, &uncompressed, 4);
  return bytes + payload;
}

// LZF made of literal runs only (a control byte n - 1 < 32, then n bytes): valid, never shorter.
std::string LzfLiterals(const std::string& raw) {
  std::string out;
  for (size_t at = 0; at < raw.size(); at += 32) {
    const std::string run = raw.substr(at, 32);
    out.push_back(static_cast<char>(run.size() - 1));
    out += run;
  }
  return out;
}

const std::string kOnePointCompressed = kXyzPcd + "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_compressed\n";

TEST(HostilePcd, BinaryCompressedReadsWhenItsSizesAgree) {
  ScratchDir dir;
  // binary_compressed stores fields one after another: x of every point, then y, then z.
  const std::string raw = Floats({1, 4, 2, 5, 3, 6});
  const std::string lzf = LzfLiterals(raw);
  WriteText(dir / "ok.pcd", kXyzPcd + "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary_compressed\n" +
                                Compressed(static_cast<uint32_t>(lzf.size()), static_cast<uint32_t>(raw.size()), lzf));
  auto reader = OpenScan(dir / "ok.pcd");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().format_version, "binary_compressed");
  PointBatch batch;
  ASSERT_EQ(*(*reader)->Read(batch, 10), 2u);
  EXPECT_EQ(batch.xyz[1], (std::array<double, 3>{4, 5, 6}));
}

TEST(HostilePcd, BinaryCompressedWithoutSizeWords) {
  ExpectRefused("c.pcd", kOnePointCompressed + "abc", StatusCode::kTruncated,
                "binary_compressed PCD ends before its two size words");
}

TEST(HostilePcd, BinaryCompressedUnpackingToAnotherSize) {
  // PCL resized its buffer to whatever the file said: here 4 GB.
  ExpectRefused("c.pcd", kOnePointCompressed + Compressed(13, 0xFFFFFFF0u, LzfLiterals(Floats({1, 2, 3}))),
                StatusCode::kMalformed, "says it unpacks to 4294967280 bytes, but 1 points of 12 bytes are 12");
}

TEST(HostilePcd, BinaryCompressedPayloadBeyondTheFile) {
  ExpectRefused("c.pcd", kOnePointCompressed + Compressed(1000, 12, LzfLiterals(Floats({1, 2, 3}))),
                StatusCode::kTruncated, "declares 1000 compressed bytes but the file holds only 13");
}

TEST(HostilePcd, BinaryCompressedClaimingMoreThanLzfCanExpand) {
  ExpectRefused("c.pcd",
                kXyzPcd + "WIDTH 100\nHEIGHT 1\nPOINTS 100\nDATA binary_compressed\n" + Compressed(1, 1200, "\x1f"),
                StatusCode::kMalformed, "1 compressed bytes unpack to 1200, more than LZF can expand them to");
  ExpectRefused("c.pcd", kOnePointCompressed + Compressed(0, 12, ""), StatusCode::kMalformed,
                "0 compressed bytes unpack to 12");
}

// PCL goes on reading header keywords after DATA; a body starting with one would replace our checked
// numbers with its own (here POINTS 2 against WIDTH 1).
TEST(HostilePcd, DataThatReadsAsAnotherHeaderLine) {
  ExpectRefused("k.pcd", kXyzPcd + "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\nPOINTS 2\n1 2 3\n",
                StatusCode::kMalformed, "PCD data begins with 'POINTS', which reads as one more header line");
  ExpectRefused("k.pcd", kXyzPcd + "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n\n#" + std::string(12, 'x'),
                StatusCode::kMalformed, "PCD data begins with '#xxxxxxxxxxxx'");
}

// ---- PCD: header structure ----

TEST(HostilePcd, InconsistentOrIncompleteHeaders) {
  const std::string tail = "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n";
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4\nTYPE F F F\n" + tail, StatusCode::kMalformed,
                "SIZE lists 2 values for 3 FIELDS");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 3\nTYPE F F F\n" + tail, StatusCode::kMalformed,
                "SIZE 3 of field 'z' is not 1, 2, 4 or 8");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\n" + tail, StatusCode::kMalformed,
                "field 'z' is a float of SIZE 2");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 1\nTYPE F F B\n" + tail, StatusCode::kUnsupported,
                "TYPE 'B' of field 'z' is not supported");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 0\n" + tail, StatusCode::kMalformed,
                "COUNT of field 'z' is zero");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
                StatusCode::kMalformed, "POINTS before the mandatory HEIGHT line");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nCOUNT 1 1 1\n", StatusCode::kMalformed,
                "COUNT comes after WIDTH");
  ExpectRefused("h.pcd", "FIELDS x y z\nTYPE F F F\nSIZE 4 4 4\n" + tail, StatusCode::kMalformed,
                "TYPE before the mandatory SIZE line");
  ExpectRefused("h.pcd", "FIELDS x y w\nSIZE 4 4 4\nTYPE F F F\n" + tail, StatusCode::kMalformed,
                "PCD file has no 'z' field");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA gzip\n1 2 3\n",
                StatusCode::kMalformed, "DATA must be ascii, binary or binary_compressed");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0\nPOINTS 1\n",
                StatusCode::kMalformed, "VIEWPOINT needs 7 numbers");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\r\n\r\n" + tail, StatusCode::kMalformed,
                "PCD header line 4 is a bare CR");
  ExpectRefused("h.pcd", "FIELDS x y z" + std::string(20000, ' ') + "\n", StatusCode::kMalformed,
                "PCD header line 1 is longer than 16384 bytes");
  ExpectRefused("h.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH\x01 1\n", StatusCode::kMalformed,
                "PCD header line 4 holds the control byte 0x01");
}

TEST(HostilePcd, TooManyFieldsOrTooLargeAPoint) {
  std::string names;
  for (int i = 0; i < 1025; ++i) names += " f" + std::to_string(i);
  ExpectRefused("f.pcd", "FIELDS" + names + "\n", StatusCode::kResourceLimit, "1025 FIELDS, more than the 1024 allowed");
  ExpectRefused("f.pcd",
                "FIELDS x y z d e\nSIZE 4 4 4 8 8\nTYPE F F F F F\nCOUNT 1 1 1 65536 65536\nWIDTH 1\nHEIGHT 1\n"
                "POINTS 1\nDATA binary\n",
                StatusCode::kResourceLimit, "PCD points of 1048588 bytes, more than the 1048576 allowed");
}

// ---- PLY: header structure ----

TEST(HostilePly, InconsistentOrIncompleteHeaders) {
  const std::string body = "end_header\n1 2 3\n";
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n" + body,
                StatusCode::kMalformed, "PLY vertex element has no 'z' property");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nelement point 1\n" + kXyzPlyProps + body, StatusCode::kMalformed,
                "PLY header declares no vertex element");
  ExpectRefused("h.ply", "ply\nelement vertex 1\n" + kXyzPlyProps + body, StatusCode::kMalformed,
                "PLY header line 2: the format line must come before 'element'");
  ExpectRefused("h.ply", "ply\nformat ascii 2.0\n", StatusCode::kUnsupported, "PLY version '2.0' is not supported");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nformat ascii 1.0\n", StatusCode::kMalformed, "a second format line");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nproperty float x\n", StatusCode::kMalformed,
                "a property before any element");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\n",
                StatusCode::kMalformed, "property 'x' of element 'vertex' is declared twice");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n", StatusCode::kMalformed,
                "unknown PLY type 'float128'");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nelement vertex -1\n", StatusCode::kMalformed,
                "element count '-1' is not a non-negative integer");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nelement vertex 1000000000000\n", StatusCode::kResourceLimit,
                "declares 1000000000000 instances, more than the 4294967295 allowed");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nvertices 1\n", StatusCode::kMalformed, "unknown keyword 'vertices'");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nelement vertex 1\n" + kXyzPlyProps, StatusCode::kMalformed,
                "PLY file ends before its header's end_header line");
  ExpectRefused("h.ply", "ply\nformat ascii 1.0\nelement vertex 0\n" + kXyzPlyProps + body, StatusCode::kMalformed,
                "PLY header declares zero vertices");
}

TEST(HostilePly, ListsInVerticesAndRangeGridsAreRefused) {
  // PCL sizes every vertex by the first one's list length: one long list, many vertices, huge buffer.
  ExpectRefused("l.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + kXyzPlyProps +
                             "property list uint float normals\nend_header\n",
                StatusCode::kUnsupported, "vertex property 'normals' is a list");
  // PCL copies range_grid entries from vertex indices it does not check.
  ExpectRefused("r.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + kXyzPlyProps +
                             "element range_grid 1\nproperty list uchar int vertex_indices\nend_header\n",
                StatusCode::kUnsupported, "range_grid elements");
}

TEST(HostilePly, ElementsAfterTheVerticesMustFitToo) {
  ExpectRefused("f.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + kXyzPlyProps +
                             "element face 1000000\nproperty list uchar int vertex_indices\nend_header\n" +
                             Floats({1, 2, 3}) + "\x03",
                StatusCode::kTruncated,
                "PLY header declares 1000000 'face' elements of at least 1 bytes but the file holds only 1 complete records");
  // Without properties an element costs no bytes, so its count would bound nothing.
  ExpectRefused("e.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + kXyzPlyProps +
                             "element nothing 4000000000\nend_header\n" + Floats({1, 2, 3}),
                StatusCode::kMalformed, "element 'nothing' declares 4000000000 instances but no properties");
}

// PCL takes obj_info num_cols × num_rows as the cloud's size and allocates it.
TEST(HostilePly, ObjInfoGridMustMatchTheVertices) {
  ExpectRefused("g.ply", "ply\nformat ascii 1.0\nobj_info num_cols 100000\nobj_info num_rows 100000\n"
                         "element vertex 1\n" + kXyzPlyProps + "end_header\n1 2 3\n",
                StatusCode::kMalformed, "obj_info num_cols × num_rows (100000 × 100000) disagrees with the 1 vertices");
  ScratchDir dir;
  WriteText(dir / "ok.ply", "ply\nformat ascii 1.0\nobj_info num_cols 2\nobj_info num_rows 1\nelement vertex 2\n" +
                                kXyzPlyProps + "end_header\n1 2 3\n4 5 6\n");
  auto reader = OpenScan(dir / "ok.ply");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().point_count, 2u);
}

// Found by the ply fuzzer: PCL writes the packed color when it reads blue, at red's place; with no
// red (here "r`d") it wrote past the point and aborted on an assertion (fuzz/regressions/ply/).
TEST(HostilePly, UcharBlueWithoutRedIsRefused) {
  const std::string head = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + kXyzPlyProps;
  const std::string point = Floats({1, 2, 3}) + "\x01\x02\x03";
  ExpectRefused("c.ply", head + "property uchar r`d\nproperty uchar green\nproperty uchar blue\nend_header\n" + point,
                StatusCode::kUnsupported, "uchar vertex colors must be one red, green, blue set with red before blue");
  ExpectRefused("c.ply", head + "property uchar blue\nproperty uchar green\nproperty uchar red\nend_header\n" + point,
                StatusCode::kUnsupported, "PLY header line 7: uchar vertex colors must be one red, green, blue set");
  ExpectRefused("c.ply", head + "property uchar red\nproperty uchar green\nend_header\n" + point.substr(0, 14),
                StatusCode::kUnsupported, "PLY uchar vertex colors must be one red, green, blue set");
}

// A one-byte property named rgb is no packed color; reading it as 4 bytes ran past the last point.
TEST(HostilePly, OneByteRgbPropertyIsNotAPackedColor) {
  ScratchDir dir;
  WriteText(dir / "c.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + kXyzPlyProps +
                               "property uchar rgb\nend_header\n" + Floats({1, 2, 3}) + "\x07");
  auto reader = OpenScan(dir / "c.ply");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_FALSE((*reader)->info().has_color);
  PointBatch batch;
  ASSERT_EQ(*(*reader)->Read(batch, 10), 1u);
  EXPECT_EQ(batch.xyz[0], (std::array<double, 3>{1, 2, 3}));
}

TEST(HostilePly, CrLfHeaderIsRead) {
  ScratchDir dir;
  WriteText(dir / "crlf.ply", "ply\r\nformat ascii 1.0\r\nelement vertex 1\r\nproperty float x\r\nproperty float y\r\n"
                              "property float z\r\nend_header\r\n1 2 3\r\n");
  auto reader = OpenScan(dir / "crlf.ply");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().format_version, "ascii");
  PointBatch batch;
  ASSERT_EQ(*(*reader)->Read(batch, 10), 1u);
  EXPECT_EQ(batch.xyz[0], (std::array<double, 3>{1, 2, 3}));
}

// ---- text from LAS records that is not UTF-8 ----

// One LASF_Projection VLR: 54-byte header, then the payload.
std::vector<uint8_t> ProjectionVlr(uint16_t record_id, const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> vlr;
  AppendLE<uint16_t>(vlr, 0);
  const char user[16] = "LASF_Projection";
  vlr.insert(vlr.end(), user, user + 16);
  AppendLE<uint16_t>(vlr, record_id);
  AppendLE<uint16_t>(vlr, static_cast<uint16_t>(payload.size()));
  vlr.resize(vlr.size() + 32, 0);
  vlr.insert(vlr.end(), payload.begin(), payload.end());
  return vlr;
}

// A LAS 1.2 file of `points` with `vlrs` between its header and its points, at Autzen's
// coordinates (EPSG:2994, feet) so that georeferencing succeeds.
std::vector<uint8_t> LasWithVlrs(const std::vector<std::vector<uint8_t>>& vlrs) {
  LasSpec spec;
  spec.minor = 2;
  spec.format = 3;
  std::vector<uint8_t> las = MakeLas(spec, testing::RandomLasPoints(200, 3));
  const double offsets[3] = {636500.0, 849200.0, 450.0};
  std::memcpy(las.data() + 155, offsets, sizeof(offsets));
  std::vector<uint8_t> all;
  for (const auto& v : vlrs) all.insert(all.end(), v.begin(), v.end());
  las.insert(las.begin() + 227, all.begin(), all.end());
  const uint32_t point_offset = static_cast<uint32_t>(227 + all.size());
  const uint32_t count = static_cast<uint32_t>(vlrs.size());
  std::memcpy(las.data() + 96, &point_offset, 4);
  std::memcpy(las.data() + 100, &count, 4);
  return las;
}

bool IsValidUtf8(std::string_view s) {
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    if (n == 0 || i + n > s.size()) return false;
    for (size_t k = 1; k < n; ++k) {
      if ((static_cast<unsigned char>(s[i + k]) & 0xC0) != 0x80) return false;
    }
    i += n;
  }
  return true;
}

// The whole encode, as the daemon's worker runs it, must end in a Status, and the metadata it
// writes must be valid UTF-8 (the raw bytes in JSON used to throw in dump() and kill the daemon).
StatusOr<nlohmann::json> EncodeAndReadBackMeta(const std::filesystem::path& las) {
  EncodeOptions options;
  options.voxel_size = 4.0;
  options.georeference = true;
  StatusOr<EncodedScan> encoded = Internal("EncodeScan threw");
  EXPECT_NO_THROW(encoded = EncodeScan(las, options));
  if (!encoded.ok()) return encoded.status();
  std::vector<uint8_t> bytes;
  EXPECT_NO_THROW(bytes = SerializePdag(encoded->file));
  EXPECT_TRUE(IsValidUtf8(DumpJson(encoded->file.meta)));
  ASSIGN_OR_RETURN(PdagFile file, ParsePdag(bytes));  // ParseJson refuses invalid UTF-8
  return file.meta;
}

TEST(LasText, GeoKeyAsciiRecordWithInvalidUtf8IsEncodedWithValidMetadata) {
  ScratchDir dir;
  const std::string citation = "NAD83 / Oregon GIC Lambert (ft) \xFF\xFE\xC3(|";
  std::vector<uint8_t> directory;
  const auto put = [&](std::initializer_list<uint16_t> words) {
    for (uint16_t w : words) AppendLE<uint16_t>(directory, w);
  };
  put({1, 1, 0, 3});        // directory version 1.1.0, 3 keys
  put({1024, 0, 1, 1});     // GTModelTypeGeoKey: projected
  put({1026, 34737, static_cast<uint16_t>(citation.size()), 0});  // GTCitationGeoKey in the ASCII record
  put({3072, 0, 1, 2994});  // ProjectedCSTypeGeoKey: EPSG:2994
  WriteBytes(dir / "geokeys.las",
             LasWithVlrs({ProjectionVlr(34735, directory),
                          ProjectionVlr(34737, std::vector<uint8_t>(citation.begin(), citation.end()))}));
  auto reader = OpenScan(dir / "geokeys.las");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().geokeys->ascii, citation);  // the reader keeps the bytes as stored

  auto meta = EncodeAndReadBackMeta(dir / "geokeys.las");
  ASSERT_TRUE(meta.ok()) << meta.status().ToString();
  const std::string ascii = (*meta)["crs"]["geokeys"]["ascii"].get<std::string>();
  EXPECT_TRUE(IsValidUtf8(ascii));
  EXPECT_NE(ascii.find("NAD83 / Oregon GIC Lambert (ft) "), std::string::npos) << ascii;
  EXPECT_EQ((*meta)["crs"]["epsg"], 2994);
}

TEST(LasText, WktRecordWithInvalidUtf8IsEncodedWithValidMetadata) {
  ScratchDir dir;
  const std::string wkt =
      "PROJCS[\"NAD83(HARN) / Oregon GIC Lambert (ft) \xFF\xC0\",GEOGCS[\"NAD83(HARN)\",DATUM[\"NAD83_HARN\","
      "SPHEROID[\"GRS 1980\",6378137,298.257222101]],PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433]],"
      "PROJECTION[\"Lambert_Conformal_Conic_2SP\"],PARAMETER[\"standard_parallel_1\",43],"
      "PARAMETER[\"standard_parallel_2\",45.5],PARAMETER[\"latitude_of_origin\",41.75],"
      "PARAMETER[\"central_meridian\",-120.5],PARAMETER[\"false_easting\",1312335.958],"
      "PARAMETER[\"false_northing\",0],UNIT[\"foot\",0.3048]]";
  std::vector<uint8_t> payload(wkt.begin(), wkt.end());
  payload.push_back(0);
  WriteBytes(dir / "wkt.las", LasWithVlrs({ProjectionVlr(2112, payload)}));
  auto reader = OpenScan(dir / "wkt.las");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().crs_wkt, wkt);

  // PROJ takes the WKT (the bad bytes are only in a name); the metadata carries it as valid UTF-8.
  auto meta = EncodeAndReadBackMeta(dir / "wkt.las");
  ASSERT_TRUE(meta.ok()) << meta.status().ToString();
  const std::string stored = (*meta)["crs"]["wkt"].get<std::string>();
  EXPECT_TRUE(IsValidUtf8(stored));
  EXPECT_NE(stored.find("Lambert_Conformal_Conic_2SP"), std::string::npos);
}

}  // namespace
}  // namespace pointdag
