#include <gtest/gtest.h>

#include <GeographicLib/Geocentric.hpp>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

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

// Two georeferencers of one CRS and origin: the first maps through the fitted polynomial.
struct FittedAndExact {
  std::unique_ptr<Georeferencer> fitted, exact;
};
FittedAndExact MakePair(const std::string& crs, const std::array<double, 3>& centre, const Bounds& bounds) {
  auto fitted = Georeferencer::Create(crs, "epsg-override", centre);
  auto exact = Georeferencer::Create(crs, "epsg-override", centre);
  EXPECT_TRUE(fitted.ok() && exact.ok());
  (*fitted)->FitLocalEnu(bounds);
  return {std::move(*fitted), std::move(*exact)};
}

TEST(Georeference, TheFittedEnuMapAgreesWithProjWithinItsToleranceInsideTheBounds) {
  // Autzen's Lambert conformal conic, 6 km x 6 km x 300 m in feet.
  const std::array<double, 3> centre{636500, 849200, 450};
  const Bounds bounds{{626500, 839200, 0}, {646500, 859200, 1000}};
  auto pair = MakePair("EPSG:2994", centre, bounds);
  const auto error = pair.fitted->frame().enu_fit_error_m;
  ASSERT_TRUE(error.has_value()) << "the polynomial should fit a 6 km box";
  EXPECT_LE(*error, Georeferencer::kLocalEnuTolerance_m);
  std::vector<std::array<double, 3>> points;
  uint64_t state = 12345;
  const auto next = [&] {  // uniform in [0, 1)
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / static_cast<double>(uint64_t{1} << 53);
  };
  for (int i = 0; i < 20000; ++i) {
    points.push_back({bounds.min[0] + next() * 20000, bounds.min[1] + next() * 20000, next() * 1000});
  }
  points.push_back({700000, 849200, 450});  // outside the bounds: the exact path, bit for bit
  auto expected = points;
  ASSERT_TRUE(pair.fitted->ToEnu(points).ok());
  ASSERT_TRUE(pair.exact->ToEnu(expected).ok());
  double worst = 0;
  for (size_t i = 0; i + 1 < points.size(); ++i) {
    worst = std::max(worst, std::hypot(points[i][0] - expected[i][0], points[i][1] - expected[i][1], points[i][2] - expected[i][2]));
  }
  EXPECT_LE(worst, Georeferencer::kLocalEnuTolerance_m);
  EXPECT_GT(worst, 0.0) << "inside the bounds the polynomial, not PROJ, maps the points";
  EXPECT_EQ(points.back(), expected.back());
}

TEST(Georeference, ABoxTooLargeForThePolynomialStaysExact) {
  // Half a continent in geographic degrees: no degree-4 polynomial is within 50 µm of that.
  const std::array<double, 3> centre{10, 45, 100};
  const Bounds bounds{{-10, 30, 0}, {30, 60, 4000}};
  auto pair = MakePair("EPSG:4979", centre, bounds);
  EXPECT_FALSE(pair.fitted->frame().enu_fit_error_m.has_value());
  std::vector<std::array<double, 3>> points = {{10, 45, 100}, {0, 50, 2000}, {25, 35, 10}};
  auto expected = points;
  ASSERT_TRUE(pair.fitted->ToEnu(points).ok());
  ASSERT_TRUE(pair.exact->ToEnu(expected).ok());
  EXPECT_EQ(points, expected);
}

TEST(Georeference, UnknownCrsIsAnError) {
  auto geo = Georeferencer::Create("EPSG:999999", "epsg-override", {0, 0, 0});
  EXPECT_EQ(geo.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(geo.status().message().find("unknown CRS"), std::string::npos);
}

// Autzen's feet in EPSG:4326 are far outside any latitude: the error names the CRS it came from.
TEST(Georeference, ACentreOutsideTheCrsDomainIsAnErrorNamingTheCrs) {
  auto geo = Georeferencer::Create("EPSG:4326", "epsg-override", {4.6e6, 1.3e6, 500});
  ASSERT_EQ(geo.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(geo.status().message().find("outside the domain of WGS 84:"), std::string::npos) << geo.status().message();
}

// A CRS is resolved once per process and its operation cloned for every later Georeferencer: those
// made at once on several threads, for other centres, transform exactly as a first one does, and a
// CRS that failed is not remembered as resolved.
TEST(Georeference, GeoreferencersOfOneCrsMadeOnManyThreadsAgree) {
  const std::string wkt = [] {
    auto first = Georeferencer::Create("EPSG:2154", "epsg-override", {650000, 6860000, 100});
    EXPECT_TRUE(first.ok());
    return first.ok() ? (*first)->frame().crs_wkt : std::string();
  }();
  ASSERT_FALSE(wkt.empty());
  const auto transform = [](const Georeferencer& g, std::array<double, 3> p) {
    EXPECT_TRUE(g.ToEnu(std::span(&p, 1)).ok());
    return p;
  };
  auto reference = Georeferencer::Create(wkt, "las-wkt", {870500, 6618500, 60});
  ASSERT_TRUE(reference.ok()) << reference.status().ToString();
  const std::array<double, 3> point = {870600, 6618400, 75};
  const std::array<double, 3> expected = transform(**reference, point);
  std::vector<std::thread> threads;
  std::vector<std::array<double, 3>> got(8);
  std::vector<std::string> names(8);
  for (size_t t = 0; t < got.size(); ++t) {
    threads.emplace_back([&, t] {
      auto g = Georeferencer::Create(wkt, "las-wkt", {870500, 6618500, 60});
      if (!g.ok()) return;
      names[t] = (*g)->frame().crs_name;
      got[t] = transform(**g, point);
    });
  }
  for (auto& thread : threads) thread.join();
  for (size_t t = 0; t < got.size(); ++t) {
    EXPECT_EQ(names[t], (*reference)->frame().crs_name);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(got[t][a], expected[a]) << "thread " << t << " axis " << a;
  }
  EXPECT_EQ((*reference)->frame().epsg, 2154);
  // 100 m east and 100 m south of the origin, in a conformal projection (turned by the meridians' convergence).
  EXPECT_NEAR(std::hypot(expected[0], expected[1]), 100 * std::sqrt(2.0), 0.2);
  for (int i = 0; i < 2; ++i) EXPECT_EQ(Georeferencer::Create("EPSG:999999", "epsg-override", {0, 0, 0}).status().code(), StatusCode::kInvalidArgument);
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
    // A scan a few km across is mapped by the fitted polynomial.
    ASSERT_TRUE(framed->frame.enu_fit_error_m.has_value()) << c.file;
    EXPECT_LE(*framed->frame.enu_fit_error_m, Georeferencer::kLocalEnuTolerance_m) << c.file;
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
  // Each file's ENU map is a polynomial fitted over its own header bounds: equal within its tolerance.
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(a->grid.origin[axis], b->grid.origin[axis], Georeferencer::kLocalEnuTolerance_m);
  }
  EXPECT_EQ(a->file.meta["frame"]["epsg"], nlohmann::json());  // user-defined WKT without an EPSG id
  EXPECT_EQ(a->file.meta["frame"]["enu_origin"], b->file.meta["frame"]["enu_origin"]);
  // The crop is about 1180 x 560 ft: in metres, 360 x 171.
  EXPECT_GT(a->grid.voxel_size * std::ldexp(1.0, a->grid.depth), 355.0);
}

}  // namespace
}  // namespace pointdag
