#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "pointdag/read/memory_reader.h"
#include "pointdag/read/pcl_reader.h"
#include "pointdag/read/remembering_reader.h"
#include "pointdag/read/scan_reader.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::DataDir;
using testing::LasSpec;
using testing::MakeLas;
using testing::ScratchDir;
using testing::WriteBytes;

struct ScanFacts {
  const char* file;
  ScanFormat format;
  uint64_t points;
  bool has_color;
  int color_bits;        // after 8-in-16 detection
  const char* wkt_part;  // substring of the WKT, "" for none
  size_t geokeys;
  std::array<double, 3> min, max;
};

// Facts cross-checked against each file's own header and README.
const ScanFacts kScans[] = {
    {"tiny_1.2-with-color_1065pts.las", ScanFormat::kLas, 1065, true, 8, "", 0,
     {635619.85, 848899.70, 406.59}, {638982.55, 853535.43, 586.38}},
    {"autzen_trim_pdrf3_rgb.las", ScanFormat::kLas, 110000, true, 8, "NAD_1983_HARN_Lambert_Conformal_Conic", 21,
     {636001.76, 848935.20, 406.26}, {637179.22, 849497.90, 520.51}},
    {"autzen_trim_las14_pdrf7_rgb.las", ScanFormat::kLas, 110000, true, 8, "NAD_1983_HARN_Lambert_Conformal_Conic", 0,
     {636001.76, 848935.20, 406.26}, {637179.22, 849497.90, 520.51}},
    {"ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las", ScanFormat::kLas, 70840, true, 16, "Lambert-93", 0,
     {870200.01, 6617083.28, 179.13}, {870299.99, 6617145.15, 194.36}},
    {"lion_takanawa_pdrf7_rgb.las", ScanFormat::kLas, 341989, true, 16, "", 0,
     {-4.99, 1.04, -3.45}, {-0.79, 6.72, 1.12}},
    {"lone_star_tls_noRGB.las", ScanFormat::kLas, 518862, false, 8, "GEOCCS", 0,
     {515368.6022, 4918340.3640, 2322.8962}, {515401.0430, 4918381.1238, 2338.5755}},
    {"pcx_guanyin_cc-by-4.0_rgb.ply", ScanFormat::kPly, 238154, true, 8, "", 0,
     {-0.5108, 0.0021, -0.3704}, {0.4749, 1.2929, 0.4535}},
    {"pcl_milk_cartoon_clorox_kinect_rgb.ply", ScanFormat::kPly, 241407, true, 8, "", 0,
     {-1.0608, -0.8692, 0.5010}, {1.1525, 0.2197, 2.0630}},
};

class RealScanTest : public ::testing::TestWithParam<ScanFacts> {};

TEST_P(RealScanTest, ReadsCountsBoundsColorsAndCrs) {
  SKIP_WITHOUT_DATA();
  const ScanFacts& f = GetParam();
  auto reader = OpenScan(DataDir() / f.file);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  const ScanInfo& info = (*reader)->info();
  EXPECT_EQ(info.format, f.format);
  EXPECT_EQ(info.point_count, f.points);
  EXPECT_EQ(info.has_color, f.has_color);
  if (*f.wkt_part) {
    EXPECT_NE(info.crs_wkt.find(f.wkt_part), std::string::npos) << info.crs_wkt;
  } else {
    EXPECT_TRUE(info.crs_wkt.empty());
  }
  EXPECT_EQ(info.geokeys ? info.geokeys->keys.size() : 0u, f.geokeys);

  auto survey = SurveyScan(**reader);
  ASSERT_TRUE(survey.ok()) << survey.status().ToString();
  EXPECT_EQ(survey->points, f.points);
  EXPECT_EQ(survey->color_bits, f.color_bits);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(survey->bounds.min[a], f.min[a], 1e-3);
    EXPECT_NEAR(survey->bounds.max[a], f.max[a], 1e-3);
  }
  // The survey rewinds: a second full read yields every point again.
  PointBatch batch;
  uint64_t total = 0;
  for (;;) {
    auto n = (*reader)->Read(batch, 100000);
    ASSERT_TRUE(n.ok());
    if (*n == 0) break;
    EXPECT_EQ(batch.rgb.size(), f.has_color ? *n : 0u);
    total += *n;
  }
  EXPECT_EQ(total, f.points);
}

INSTANTIATE_TEST_SUITE_P(SharedData, RealScanTest, ::testing::ValuesIn(kScans), testing::ScanFileName());

TEST(LasReader, AutzenGeoKeysNameUserDefinedProjectionAndFeet) {
  SKIP_WITHOUT_DATA();
  auto reader = OpenScan(DataDir() / "autzen_trim_pdrf3_rgb.las");
  ASSERT_TRUE(reader.ok());
  const auto& keys = (*reader)->info().geokeys;
  ASSERT_TRUE(keys.has_value());
  bool user_defined_projection = false, feet = false;
  for (const GeoKey& k : keys->keys) {
    if (k.id == 3072 && k.value == 32767) user_defined_projection = true;  // ProjectedCSTypeGeoKey
    if (k.id == 3076 && k.value == 9002) feet = true;                      // ProjLinearUnitsGeoKey = foot
  }
  EXPECT_TRUE(user_defined_projection);
  EXPECT_TRUE(feet);
  EXPECT_FALSE(keys->ascii.empty());
  EXPECT_EQ(keys->doubles.size(), 9u);
}

// Every point data record format 0-10 in LAS 1.4 (and 0-3 in 1.2), with and without extra bytes.
TEST(LasReader, ReadsEveryPointFormatAndSkipsExtraBytes) {
  ScratchDir dir;
  const auto points = testing::RandomLasPoints(300, 7);
  for (int minor : {2, 4}) {
    for (int format = 0; format <= (minor == 2 ? 3 : 10); ++format) {
      for (int extra : {0, 5}) {
        LasSpec spec;
        spec.minor = minor;
        spec.format = format;
        spec.extra_bytes = extra;
        spec.legacy_count = format < 6;
        const auto path = dir / ("f" + std::to_string(minor) + "_" + std::to_string(format) + "_" + std::to_string(extra) + ".las");
        WriteBytes(path, MakeLas(spec, points));
        auto reader = OpenScan(path);
        ASSERT_TRUE(reader.ok()) << "format " << format << ": " << reader.status().ToString();
        const bool color = testing::kRgbAt[format] != 0;
        EXPECT_EQ((*reader)->info().has_color, color) << format;
        PointBatch batch;
        auto n = (*reader)->Read(batch, 1000);
        ASSERT_TRUE(n.ok());
        ASSERT_EQ(*n, points.size());
        for (size_t i = 0; i < points.size(); ++i) {
          for (int a = 0; a < 3; ++a) EXPECT_DOUBLE_EQ(batch.xyz[i][a], points[i].xyz[a] * spec.scale + spec.offset);
          if (color) {
            EXPECT_EQ(batch.rgb[i], points[i].rgb) << "format " << format << " point " << i;
          }
        }
      }
    }
  }
}

TEST(LasReader, KeepsWktVlr) {
  ScratchDir dir;
  LasSpec spec;
  spec.wkt = "PROJCS[\"RGF93 v1 / Lambert-93\",AUTHORITY[\"EPSG\",\"2154\"]]";
  WriteBytes(dir / "wkt.las", MakeLas(spec, testing::RandomLasPoints(10)));
  auto reader = OpenScan(dir / "wkt.las");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().crs_wkt, spec.wkt);
}

TEST(LasReader, DetectsEightBitColorInSixteenBitFields) {
  ScratchDir dir;
  auto points = testing::RandomLasPoints(100, 3);
  for (auto& p : points) p.rgb = {static_cast<uint16_t>(p.rgb[0] & 0xFF), static_cast<uint16_t>(p.rgb[1] & 0xFF), 255};
  WriteBytes(dir / "c8.las", MakeLas({}, points));
  auto reader = OpenScan(dir / "c8.las");
  ASSERT_TRUE(reader.ok());
  auto survey = SurveyScan(**reader);
  ASSERT_TRUE(survey.ok());
  EXPECT_EQ(survey->color_bits, 8);
  points[5].rgb[0] = 256;
  WriteBytes(dir / "c16.las", MakeLas({}, points));
  auto reader16 = OpenScan(dir / "c16.las");
  ASSERT_TRUE(reader16.ok());
  EXPECT_EQ(SurveyScan(**reader16)->color_bits, 16);
}

// ---- Malformed input: a typed error naming the problem, never a crash or a huge allocation ----

class MalformedLas : public ::testing::Test {
 protected:
  std::vector<uint8_t> Good() { return MakeLas({}, testing::RandomLasPoints(50)); }
  Status Open(const std::vector<uint8_t>& bytes) {
    WriteBytes(dir_ / "bad.las", bytes);
    auto reader = OpenScan(dir_ / "bad.las");
    if (!reader.ok()) return reader.status();
    auto survey = SurveyScan(**reader);
    return survey.ok() ? Status::Ok() : survey.status();
  }
  template <typename T>
  static void Put(std::vector<uint8_t>& b, size_t at, T v) { std::memcpy(b.data() + at, &v, sizeof(v)); }
  ScratchDir dir_;
};

TEST_F(MalformedLas, TruncatedPointData) {
  auto b = Good();
  b.resize(b.size() - 10);
  const Status s = Open(b);
  EXPECT_EQ(s.code(), StatusCode::kTruncated);
  EXPECT_NE(s.message().find("declares 50 points"), std::string::npos) << s.message();
}

TEST_F(MalformedLas, TruncatedHeader) {
  auto b = Good();
  b.resize(100);
  EXPECT_EQ(Open(b).code(), StatusCode::kTruncated);
}

TEST_F(MalformedLas, CountLargerThanFile) {
  auto b = Good();
  Put<uint64_t>(b, 247, 51);
  EXPECT_EQ(Open(b).code(), StatusCode::kTruncated);
}

TEST_F(MalformedLas, AbsurdCountIsRefusedBeforeAllocating) {
  auto b = Good();
  Put<uint64_t>(b, 247, 1'000'000'000'000ull);
  const Status s = Open(b);
  EXPECT_EQ(s.code(), StatusCode::kTruncated);
  EXPECT_NE(s.message().find("1000000000000"), std::string::npos) << s.message();
}

TEST_F(MalformedLas, RecordLengthTooSmallForFormat) {
  auto b = Good();
  Put<uint16_t>(b, 105, 20);  // format 7 needs 36
  const Status s = Open(b);
  EXPECT_EQ(s.code(), StatusCode::kMalformed);
  EXPECT_NE(s.message().find("record length 20"), std::string::npos) << s.message();
}

TEST_F(MalformedLas, ZeroPoints) {
  EXPECT_EQ(Open(MakeLas({}, {})).code(), StatusCode::kMalformed);
}

TEST_F(MalformedLas, NonFiniteScale) {
  auto b = Good();
  Put<double>(b, 139, std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(Open(b).code(), StatusCode::kMalformed);
}

TEST_F(MalformedLas, InfiniteCoordinates) {
  auto b = Good();
  Put<double>(b, 131, 1e308);  // finite scale, but scale * X overflows to infinity
  const Status s = Open(b);
  EXPECT_EQ(s.code(), StatusCode::kMalformed);
  EXPECT_NE(s.message().find("not finite"), std::string::npos) << s.message();
}

TEST_F(MalformedLas, PointDataOffsetPastEnd) {
  auto b = Good();
  Put<uint32_t>(b, 96, static_cast<uint32_t>(b.size() + 10));
  EXPECT_EQ(Open(b).code(), StatusCode::kMalformed);
}

TEST_F(MalformedLas, VlrCountLies) {
  auto b = Good();
  Put<uint32_t>(b, 100, 4'000'000'000u);
  EXPECT_EQ(Open(b).code(), StatusCode::kMalformed);
}

TEST_F(MalformedLas, UnknownVersionAndFormat) {
  auto b = Good();
  b[25] = 9;
  EXPECT_EQ(Open(b).code(), StatusCode::kUnsupported);
  b = Good();
  b[104] = 11;
  EXPECT_EQ(Open(b).code(), StatusCode::kUnsupported);
}

TEST_F(MalformedLas, LazFlagWithoutItsVlrIsMalformed) {
  auto b = Good();
  b[104] |= 0x80;  // LASzip sets the top bit of the point format, and adds its VLR
  const Status s = Open(b);
  EXPECT_EQ(s.code(), StatusCode::kMalformed);
  EXPECT_NE(s.message().find("no LASzip VLR"), std::string::npos) << s.message();
}

TEST(ScanReader, RefusesUnknownAndEmptyFiles) {
  ScratchDir dir;
  WriteBytes(dir / "empty.las", {});
  EXPECT_EQ(OpenScan(dir / "empty.las").status().code(), StatusCode::kMalformed);
  WriteBytes(dir / "junk.bin", {'G', 'I', 'F', '8', '9', 'a', 0, 0});
  EXPECT_EQ(OpenScan(dir / "junk.bin").status().code(), StatusCode::kUnsupported);
  EXPECT_EQ(OpenScan(dir / "missing.las").status().code(), StatusCode::kIoError);
}

// ---- PLY and PCD through PCL ----

void WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
}

// The scan opens, and its survey refuses it as malformed, naming point 1 (the second).
void ExpectMalformedAtPointOne(const std::filesystem::path& path) {
  auto reader = OpenScan(path);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  const auto survey = SurveyScan(**reader);
  ASSERT_FALSE(survey.ok());
  EXPECT_EQ(survey.status().code(), StatusCode::kMalformed);
  EXPECT_NE(survey.status().message().find("point 1"), std::string::npos) << survey.status().message();
}

TEST(PclReader, AsciiPlyWithDoubleCoordinatesAndFloatColors) {
  ScratchDir dir;
  WriteText(dir / "a.ply",
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
            "property float red\nproperty float green\nproperty float blue\nend_header\n"
            "6617083.25 870200.5 10 1.0 0.5 0\n6617084.75 870201.5 11 0 0.25 1\n");
  auto reader = OpenScan(dir / "a.ply");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  PointBatch batch;
  ASSERT_EQ(*(*reader)->Read(batch, 10), 2u);
  EXPECT_DOUBLE_EQ(batch.xyz[0][0], 6617083.25);  // doubles survive: no float rounding of big coordinates
  EXPECT_DOUBLE_EQ(batch.xyz[1][1], 870201.5);
  EXPECT_EQ(batch.rgb[0], (std::array<uint16_t, 3>{255, 128, 0}));
  EXPECT_EQ(batch.rgb[1], (std::array<uint16_t, 3>{0, 64, 255}));
}

TEST(PclReader, BinaryBigEndianPlyWithUcharColors) {
  ScratchDir dir;
  std::string text = "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                     "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  const float xyz[3] = {1.5f, -2.0f, 3.25f};
  for (float v : xyz) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    for (int s = 24; s >= 0; s -= 8) text.push_back(static_cast<char>((u >> s) & 0xFF));
  }
  text += std::string{'\x0a', '\x14', '\x1e'};
  WriteText(dir / "be.ply", text);
  auto reader = OpenScan(dir / "be.ply");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  PointBatch batch;
  ASSERT_EQ(*(*reader)->Read(batch, 10), 1u);
  EXPECT_EQ(batch.xyz[0], (std::array<double, 3>{1.5, -2.0, 3.25}));
  EXPECT_EQ(batch.rgb[0], (std::array<uint16_t, 3>{10, 20, 30}));
}

// An ASCII PLY of float x, y, z only, one vertex per row.
void WriteXyzPly(const std::filesystem::path& path, const std::vector<std::string>& rows) {
  std::string text = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(rows.size()) +
                     "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (const std::string& row : rows) text += row + "\n";
  WriteText(path, text);
}

TEST(PclReader, PlyWithoutColorHasNoColor) {
  ScratchDir dir;
  WriteXyzPly(dir / "n.ply", {"1 2 3"});
  auto reader = OpenScan(dir / "n.ply");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_FALSE((*reader)->info().has_color);
}

TEST(PclReader, NanCoordinateIsAnError) {
  ScratchDir dir;
  WriteXyzPly(dir / "nan.ply", {"1 2 3", "nan 2 3"});
  ExpectMalformedAtPointOne(dir / "nan.ply");
}

TEST(PclReader, TruncatedBinaryPlyIsAnError) {
  SKIP_WITHOUT_DATA();
  ScratchDir dir;
  auto bytes = testing::ReadBytes(DataDir() / "pcx_guanyin_cc-by-4.0_rgb.ply");
  bytes.resize(bytes.size() / 2);
  WriteBytes(dir / "cut.ply", bytes);
  const auto reader = OpenScan(dir / "cut.ply");
  ASSERT_FALSE(reader.ok());
  EXPECT_TRUE(reader.status().code() == StatusCode::kMalformed || reader.status().code() == StatusCode::kTruncated);
}

TEST(PclReader, PlyDeclaringAbsurdCountIsAnError) {
  ScratchDir dir;
  WriteText(dir / "huge.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n"
                              "property float y\nproperty float z\nend_header\n");
  EXPECT_FALSE(OpenScan(dir / "huge.ply").ok());
}

// ---- Binary little-endian PLY read by our own code (ply_reader.h) ----

// Every point of `path` through OpenScan and through PCL, in batches of 3, twice (a rewind between).
void ExpectSameAsPcl(const std::filesystem::path& path) {
  auto ours = OpenScan(path);
  auto pcl = OpenPclScan(path, ScanFormat::kPly);
  ASSERT_TRUE(ours.ok() && pcl.ok()) << ours.status().ToString() << pcl.status().ToString();
  EXPECT_EQ((*ours)->info().has_color, (*pcl)->info().has_color);
  EXPECT_EQ((*ours)->info().point_count, (*pcl)->info().point_count);
  EXPECT_EQ((*ours)->info().format_version, (*pcl)->info().format_version);
  for (int pass = 0; pass < 2; ++pass) {
    PointBatch a, b;
    for (;;) {
      const auto na = (*ours)->Read(a, 3), nb = (*pcl)->Read(b, 3);
      ASSERT_TRUE(na.ok() && nb.ok());
      ASSERT_EQ(*na, *nb);
      if (*na == 0) break;
      EXPECT_EQ(a.xyz, b.xyz);
      EXPECT_EQ(a.rgb, b.rgb);
    }
    EXPECT_EQ((*ours)->max_color_seen(), (*pcl)->max_color_seen());
    ASSERT_TRUE((*ours)->Rewind().ok() && (*pcl)->Rewind().ok());
  }
}

template <class T>
void Put(std::string& out, T v) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof(T));
  out.append(bytes, sizeof(T));
}

TEST(PlainPlyReader, GivesWhatPclGivesForEveryLayoutItTakesOrLeaves) {
  ScratchDir dir;
  // float xyz with a property between, uchar colors: ours.
  std::string a = "ply\nformat binary_little_endian 1.0\nelement vertex 7\nproperty float x\nproperty float intensity\n"
                  "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                  "end_header\n";
  // double xyz, no color, then another element: ours.
  std::string b = "ply\r\nformat binary_little_endian 1.0\r\nelement vertex 7\r\nproperty double x\r\nproperty double y\r\n"
                  "property double z\r\nproperty short nx\r\nelement face 0\r\nproperty list uchar int vertex_indices\r\n"
                  "end_header\r\n";
  // float colors: PCL's.
  std::string c = "ply\nformat binary_little_endian 1.0\nelement vertex 7\nproperty float x\nproperty float y\n"
                  "property float z\nproperty float red\nproperty float green\nproperty float blue\nend_header\n";
  for (int i = 0; i < 7; ++i) {
    const float k = static_cast<float>(i);
    const float f[3] = {1.5f * k, -2.0f + k, 1e6f + 0.125f * k};
    Put(a, f[0]);
    Put(a, 7.0f);
    Put(a, f[1]);
    Put(a, f[2]);
    a += std::string{static_cast<char>(10 * i), static_cast<char>(255 - i), static_cast<char>(3 * i)};
    for (float v : f) Put(b, 1e7 + v / 3.0);
    Put(b, int16_t{-5});
    for (float v : f) Put(c, v);
    for (float v : {0.5f, 0.25f * k / 7, 1.0f}) Put(c, v);
  }
  WriteText(dir / "a.ply", a);
  WriteText(dir / "b.ply", b);
  WriteText(dir / "c.ply", c);
  ExpectSameAsPcl(dir / "a.ply");
  ExpectSameAsPcl(dir / "b.ply");
  ExpectSameAsPcl(dir / "c.ply");
}

TEST(PlainPlyReader, NonFiniteCoordinateIsAnErrorNamingThePoint) {
  ScratchDir dir;
  std::string text = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                     "property float z\nend_header\n";
  for (float v : {1.0f, 2.0f, 3.0f, 1.0f, std::numeric_limits<float>::infinity(), 3.0f}) Put(text, v);
  WriteText(dir / "inf.ply", text);
  ExpectMalformedAtPointOne(dir / "inf.ply");
}

TEST(PlainPlyReader, RealScansAsPclReadsThem) {
  SKIP_WITHOUT_DATA();
  ExpectSameAsPcl(DataDir() / "pcx_guanyin_cc-by-4.0_rgb.ply");
  ExpectSameAsPcl(DataDir() / "pcl_milk_cartoon_clorox_kinect_rgb.ply");
}

TEST(PclReader, ReadsAsciiAndBinaryPcdWithPackedRgb) {
  ScratchDir dir;
  // PCL packs rgb as the float whose bits are 0x00RRGGBB; 0x00FF8000 -> (255, 128, 0).
  const uint32_t packed = 0x00FF8000u;
  float as_float;
  std::memcpy(&as_float, &packed, 4);
  char rgb_text[64];
  std::snprintf(rgb_text, sizeof(rgb_text), "%.10e", static_cast<double>(as_float));
  WriteText(dir / "a.pcd", std::string("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\n"
                                       "COUNT 1 1 1 1\nWIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n"
                                       "0.5 1.5 2.5 ") + rgb_text + "\n");
  auto reader = OpenScan(dir / "a.pcd");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ((*reader)->info().format, ScanFormat::kPcd);
  PointBatch batch;
  ASSERT_EQ(*(*reader)->Read(batch, 10), 1u);
  EXPECT_EQ(batch.xyz[0], (std::array<double, 3>{0.5, 1.5, 2.5}));
  EXPECT_EQ(batch.rgb[0], (std::array<uint16_t, 3>{255, 128, 0}));

  std::string bin = "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                    "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n";
  const float pts[2][3] = {{1, 2, 3}, {4, 5, 6}};
  const uint32_t colors[2] = {0x00102030u, 0x00FFFFFFu};
  for (int i = 0; i < 2; ++i) {
    bin.append(reinterpret_cast<const char*>(pts[i]), 12);
    bin.append(reinterpret_cast<const char*>(&colors[i]), 4);
  }
  WriteText(dir / "b.pcd", bin);
  auto breader = OpenScan(dir / "b.pcd");
  ASSERT_TRUE(breader.ok()) << breader.status().ToString();
  ASSERT_EQ(*(*breader)->Read(batch, 10), 2u);
  EXPECT_EQ(batch.xyz[1], (std::array<double, 3>{4, 5, 6}));
  EXPECT_EQ(batch.rgb[0], (std::array<uint16_t, 3>{0x10, 0x20, 0x30}));
}

TEST(PclReader, TruncatedBinaryPcdIsAnError) {
  ScratchDir dir;
  std::string bin = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 100\nHEIGHT 1\n"
                    "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 100\nDATA binary\n" + std::string(40, '\0');
  WriteText(dir / "cut.pcd", bin);
  EXPECT_FALSE(OpenScan(dir / "cut.pcd").ok());
}

// Every pass (partial first pass, rewinds mid-scan, whole passes) gives the wrapped reader's points
// in order, whether the scan fits in memory or outgrows it part way.
TEST(RememberingReader, PassesGiveTheSamePointsAsTheWrappedReader) {
  std::vector<std::array<double, 3>> xyz;
  std::vector<std::array<uint16_t, 3>> rgb;
  for (int i = 0; i < 1000; ++i) {
    xyz.push_back({i * 0.5, -i * 1.0, i * 0.25});
    rgb.push_back({static_cast<uint16_t>(i), static_cast<uint16_t>(2 * i), static_cast<uint16_t>(3 * i)});
  }
  const auto pass = [](ScanReader& reader, size_t batch_points, size_t stop_after) {
    PointBatch all, batch;
    for (;;) {
      auto n = reader.Read(batch, batch_points);
      EXPECT_TRUE(n.ok());
      if (!n.ok() || *n == 0) break;
      EXPECT_EQ(batch.size(), *n);
      all.xyz.insert(all.xyz.end(), batch.xyz.begin(), batch.xyz.end());
      all.rgb.insert(all.rgb.end(), batch.rgb.begin(), batch.rgb.end());
      if (all.size() >= stop_after) break;
    }
    EXPECT_TRUE(reader.Rewind().ok());
    return all;
  };
  for (const uint64_t limit : {uint64_t{10000}, uint64_t{1000}, uint64_t{700}, uint64_t{0}}) {
    RememberingReader reader(std::make_unique<MemoryScanReader>(xyz, rgb), limit);
    const PointBatch sample = pass(reader, 300, 300);
    ASSERT_EQ(sample.size(), 300u);
    EXPECT_TRUE(std::equal(sample.xyz.begin(), sample.xyz.end(), xyz.begin()));
    for (const size_t batch_points : {size_t{256}, size_t{77}, size_t{4096}}) {
      const PointBatch whole = pass(reader, batch_points, SIZE_MAX);
      EXPECT_EQ(whole.xyz, xyz) << limit;
      EXPECT_EQ(whole.rgb, rgb) << limit;
      EXPECT_EQ(reader.max_color_seen(), 2997);
      EXPECT_EQ(reader.info().point_count, 1000u);
    }
  }
}

}  // namespace
}  // namespace pointdag
