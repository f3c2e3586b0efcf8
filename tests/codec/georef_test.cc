#include <gtest/gtest.h>

#include <GeographicLib/Geocentric.hpp>
#include <cmath>

#include "pointdag/georef/georeference.h"
#include "pointdag/pipeline.h"
#include "test_util.h"

namespace pointdag {
namespace {

constexpr double kFoot = 0.3048;

TEST(Georeference, AutzenPointMatchesCs2cs) {
  // `echo 636500 849200 450 | cs2cs -f %.10f EPSG:2994 EPSG:4979` -> 44.0506751845 -123.0715321966.
  // cs2cs passes Z through; EPSG:2994 has no vertical axis, so we take Z in its unit, feet.
  auto geo = Georeferencer::Create("EPSG:2994", "epsg-override", {636500, 849200, 450});
  ASSERT_TRUE(geo.ok()) << geo.status().ToString();
  std::array<double, 3> p{636500, 849200, 450};
  ASSERT_TRUE((*geo)->ToGeographic(std::span(&p, 1)).ok());
  EXPECT_NEAR(p[0], 44.0506751845, 1e-8);  // 1e-8 degrees: about a millimetre
  EXPECT_NEAR(p[1], -123.0715321966, 1e-8);
  EXPECT_NEAR(p[2], 450 * kFoot, 1e-6);
  const GeoFrame& frame = (*geo)->frame();
  EXPECT_TRUE(frame.georeferenced);
  EXPECT_EQ(frame.epsg, 2994);
  EXPECT_NEAR(frame.vertical_unit_m, kFoot, 1e-12);
  EXPECT_NEAR(frame.origin_llh[0], 44.0506751845, 1e-8);
}

TEST(Georeference, EnuIsMetresAboutTheOriginAndTheMatrixMapsToEcef) {
  const std::array<double, 3> centre{636500, 849200, 450};
  auto geo = Georeferencer::Create("EPSG:2994", "epsg-override", centre);
  ASSERT_TRUE(geo.ok());
  std::array<std::array<double, 3>, 3> points = {centre, centre, centre};
  points[1][0] += 1000;  // 1000 ft east
  points[2][2] += 100;   // 100 ft up
  const auto geographic = [&] {
    auto copy = points;
    EXPECT_TRUE((*geo)->ToGeographic(copy).ok());
    return copy;
  }();
  ASSERT_TRUE((*geo)->ToEnu(points).ok());
  for (double c : points[0]) EXPECT_NEAR(c, 0.0, 1e-6);
  // Lambert's scale error is well below 0.1%; grid north is not true north: at 2.5 degrees west of
  // the zone's central meridian the grid is turned by (2.5 sin 44)° = 1.8°.
  EXPECT_NEAR(std::hypot(points[1][0], points[1][1]), 304.8, 304.8 * 1e-3);
  EXPECT_NEAR(std::atan2(points[1][1], points[1][0]) * 180 / M_PI, 1.8, 0.1);
  EXPECT_NEAR(points[2][2], 30.48, 1e-6);
  const auto& m = (*geo)->frame().enu_to_ecef;
  for (size_t i = 0; i < points.size(); ++i) {
    double ecef[3];
    GeographicLib::Geocentric::WGS84().Forward(geographic[i][0], geographic[i][1], geographic[i][2], ecef[0], ecef[1], ecef[2]);
    for (int row = 0; row < 3; ++row) {
      const double mapped = m[row] * points[i][0] + m[4 + row] * points[i][1] + m[8 + row] * points[i][2] + m[12 + row];
      EXPECT_NEAR(mapped, ecef[row], 1e-3) << "point " << i << " row " << row;
    }
  }
}

TEST(Georeference, UnknownCrsIsAnError) {
  auto geo = Georeferencer::Create("EPSG:999999", "epsg-override", {0, 0, 0});
  EXPECT_EQ(geo.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(geo.status().message().find("unknown CRS"), std::string::npos);
}

TEST(Georeference, FindsTheCrsOfEachSharedScan) {
  SKIP_WITHOUT_DATA();
  struct Case {
    const char* file;
    const char* source;
    double lat, lon;  // the ENU origin, to 0.05 degrees
  };
  for (const Case& c : {Case{"autzen_trim_pdrf3_rgb.las", "las-wkt", 44.05, -123.07},
                        Case{"autzen_trim_las14_pdrf7_rgb.las", "las-wkt", 44.05, -123.07},
                        Case{"ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las", "las-wkt", 46.64, 5.23}}) {
    auto framed = OpenScanInFrame(testing::DataDir() / c.file, std::nullopt);
    ASSERT_TRUE(framed.ok()) << c.file << ": " << framed.status().ToString();
    EXPECT_TRUE(framed->frame.georeferenced);
    EXPECT_EQ(framed->frame.crs_source, c.source) << c.file;
    EXPECT_NEAR(framed->frame.origin_llh[0], c.lat, 0.05) << c.file;
    EXPECT_NEAR(framed->frame.origin_llh[1], c.lon, 0.05) << c.file;
  }
  for (const char* local : {"tiny_1.2-with-color_1065pts.las", "lion_takanawa_pdrf7_rgb.las", "pcx_guanyin_cc-by-4.0_rgb.ply"}) {
    auto framed = OpenScanInFrame(testing::DataDir() / local, std::nullopt);
    ASSERT_TRUE(framed.ok()) << local;
    EXPECT_FALSE(framed->frame.georeferenced) << local;
    EXPECT_EQ(framed->frame.crs_source, "none");
  }
}

TEST(Georeference, AWrongStoredCrsIsRefusedAndAnOverrideFixesIt) {
  SKIP_WITHOUT_DATA();
  // lone_star's WKT says geocentric WGS84; its coordinates are UTM 12N.
  auto wrong = OpenScanInFrame(testing::DataDir() / "lone_star_tls_noRGB.las", std::nullopt);
  ASSERT_EQ(wrong.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(wrong.status().message().find("geocentric"), std::string::npos) << wrong.status().message();
  auto fixed = OpenScanInFrame(testing::DataDir() / "lone_star_tls_noRGB.las", 26912);
  ASSERT_TRUE(fixed.ok()) << fixed.status().ToString();
  EXPECT_EQ(fixed->frame.crs_source, "epsg-override");
  EXPECT_GT(fixed->frame.origin_llh[1], -114.0);  // zone 12 spans 114W..108W
  EXPECT_LT(fixed->frame.origin_llh[1], -108.0);
}

TEST(Georeference, BothAutzenFilesVoxelizeToTheSameEnuGrid) {
  SKIP_WITHOUT_DATA();
  EncodeOptions options;
  options.voxel_size = 1.0;  // metres, in ENU
  options.georeference = true;
  auto a = EncodeScan(testing::DataDir() / "autzen_trim_pdrf3_rgb.las", options);
  auto b = EncodeScan(testing::DataDir() / "autzen_trim_las14_pdrf7_rgb.las", options);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->grid.morton, b->grid.morton);
  EXPECT_EQ(a->grid.origin, b->grid.origin);
  EXPECT_EQ(a->file.meta["frame"]["epsg"], nlohmann::json());  // user-defined WKT without an EPSG id
  EXPECT_EQ(a->file.meta["frame"]["enu_origin"], b->file.meta["frame"]["enu_origin"]);
  // The crop is about 1180 x 560 ft: in metres, 360 x 171.
  EXPECT_GT(a->grid.voxel_size * std::ldexp(1.0, a->grid.depth), 355.0);
}

}  // namespace
}  // namespace pointdag
