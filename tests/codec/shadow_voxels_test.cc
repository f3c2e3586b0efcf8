// Exact per-voxel shadows (issue #16, voxel_shadows.h) against brute force and analytic shadows.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "pointdag/dag/dag_builder.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/shadow/light.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/voxelize/morton.h"
#include "pointdag/voxelize/voxelizer.h"
#include "shadow_brute_force.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::BruteForceShadows;
using testing::Shadows;
using Cell = std::array<uint32_t, 3>;

Svdag DagOf(std::vector<uint64_t> codes, int depth, CountMode mode = CountMode::kLeaves) {
  std::sort(codes.begin(), codes.end());
  codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
  auto dag = BuildDag(codes, depth, {.mode = mode});
  EXPECT_TRUE(dag.ok()) << dag.status().ToString();
  return std::move(dag.value());
}

Light MakeLight(double x, double y, double z) {
  auto light = LightFromDirection(x, y, z);
  EXPECT_TRUE(light.ok()) << light.status().ToString();
  return light.value();
}

// Index of the first disagreement, or -1; reports the voxel.
void ExpectSame(const std::vector<uint8_t>& got, const std::vector<uint8_t>& want, const std::vector<uint64_t>& codes,
                const std::string& what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  size_t wrong = 0, first = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    if (got[i] != want[i] && wrong++ == 0) first = i;
  }
  if (wrong) {
    const Cell c = MortonDecode(codes[first]);
    ADD_FAILURE() << what << ": " << wrong << " of " << got.size() << " voxels differ; first (" << c[0] << ", "
                  << c[1] << ", " << c[2] << ") got " << int(got[first]) << " want " << int(want[first]);
  }
}

// ---------------------------------------------------------------------------------------------
// The predicate and the light.

TEST(RayMeetsCell, HalfLineAgainstClosedCubes) {
  const std::array<double, 3> down{0, 0, -1};  // the light travels down: rays go up
  EXPECT_TRUE(RayMeetsCell({0.5, 0.5, 0.5}, down, {0, 0, 5}));
  EXPECT_FALSE(RayMeetsCell({0.5, 0.5, 1.5}, down, {0, 0, 0}));  // behind the origin: t < 0
  EXPECT_FALSE(RayMeetsCell({0.5, 0.5, 0.5}, down, {1, 0, 3}));
  EXPECT_TRUE(RayMeetsCell({0.5, 0.5, 1.5}, {0, 0, 1}, {0, 0, 0}));
  // A ray on the shared face of two columns meets both closed cubes.
  EXPECT_TRUE(RayMeetsCell({1.0, 0.5, 0.5}, down, {0, 0, 2}));
  EXPECT_TRUE(RayMeetsCell({1.0, 0.5, 0.5}, down, {1, 0, 2}));
  EXPECT_FALSE(RayMeetsCell({1.0, 0.5, 0.5}, down, {2, 0, 2}));
  // (1, 0, -1): from (1.5, _, 0.5) the ray passes exactly through the edge at x = 1, z = 1.
  const Light diagonal = MakeLight(1, 0, -1);
  EXPECT_TRUE(RayMeetsCell({1.5, 0.5, 0.5}, diagonal.travel, {0, 0, 0}));
  EXPECT_TRUE(RayMeetsCell({1.5, 0.5, 0.5}, diagonal.travel, {1, 0, 1}));
  EXPECT_TRUE(RayMeetsCell({1.5, 0.5, 0.5}, diagonal.travel, {0, 0, 1}));
  EXPECT_FALSE(RayMeetsCell({1.5, 0.5, 0.5}, diagonal.travel, {2, 0, 1}));
  // (1, 1, -1) through the corner (1, 1, 1): every cube with that corner is met, even one the
  // ray touches at that single point only.
  const Light corner = MakeLight(1, 1, -1);
  for (const Cell& c : {Cell{0, 0, 1}, Cell{1, 0, 1}, Cell{0, 1, 0}, Cell{1, 0, 0}, Cell{0, 0, 0}}) {
    EXPECT_TRUE(RayMeetsCell({1.5, 1.5, 0.5}, corner.travel, c)) << c[0] << c[1] << c[2];
  }
  EXPECT_FALSE(RayMeetsCell({1.5, 1.5, 0.5}, corner.travel, {2, 1, 1}));
  EXPECT_FALSE(RayMeetsCell({1.5, 1.5, 0.5}, corner.travel, {1, 1, 2}));
}

TEST(LightFromDirection, NormalizesAndRejectsNoDirection) {
  const Light l = MakeLight(3, 0, -4);
  EXPECT_DOUBLE_EQ(l.travel[0], 0.6);
  EXPECT_DOUBLE_EQ(l.travel[2], -0.8);
  EXPECT_FALSE(l.below_horizon);
  const Light tiny = MakeLight(1e-310, 0, 0);  // subnormal but a direction
  EXPECT_EQ(tiny.travel[0], 1.0);
  for (auto [x, y, z] : {std::array<double, 3>{0, 0, 0}, {NAN, 0, -1}, {0, INFINITY, -1}, {-0.0, 0, -0.0}}) {
    auto bad = LightFromDirection(x, y, z);
    ASSERT_FALSE(bad.ok());
    EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  }
}

// ---------------------------------------------------------------------------------------------
// A solid box on a plane, shadows worked out by hand.

constexpr int kPlaneDepth = 5;  // 32^3 grid; plane z = 0, box [10, 13] x [10, 13] x [1, 4]

bool InBox(const Cell& c) { return c[0] >= 10 && c[0] <= 13 && c[1] >= 10 && c[1] <= 13 && c[2] >= 1 && c[2] <= 4; }

std::vector<uint64_t> BoxOnPlane() {
  std::vector<uint64_t> codes;
  for (uint32_t x = 0; x < 32; ++x) {
    for (uint32_t y = 0; y < 32; ++y) {
      codes.push_back(MortonEncode(x, y, 0));
      for (uint32_t z = 1; z <= 4; ++z) {
        if (InBox({x, y, z})) codes.push_back(MortonEncode(x, y, z));
      }
    }
  }
  std::sort(codes.begin(), codes.end());
  return codes;
}

struct PlaneCase {
  std::array<double, 3> travel;
  // Plane voxels in shadow: x in [x0, x1], y in [y0, y1]. Box voxels below the top layer are in
  // shadow of the voxel above for every case here (steep enough to leave through the top face).
  uint32_t x0, x1, y0, y1;
};

TEST(ShadowedVoxels, BoxOnPlaneMatchesTheAnalyticShadow) {
  // Slope 2 (one across per two up): from (x + .5, .5) the ray reaches the box's top corner row
  // x = 14 at height 2x - 26.5, below 5 for x <= 15, and never grazes a cell edge exactly.
  const PlaneCase cases[] = {
      {{0, 0, -1}, 10, 13, 10, 13},
      {{1, 0, -2}, 10, 15, 10, 13},
      {{-1, 0, -2}, 8, 13, 10, 13},
      {{0, 1, -2}, 10, 13, 10, 15},
      {{0, -1, -2}, 10, 13, 8, 13},
  };
  const std::vector<uint64_t> codes = BoxOnPlane();
  for (CountMode mode : {CountMode::kLeaves, CountMode::kMipmap}) {
    const Svdag dag = DagOf(codes, kPlaneDepth, mode);
    for (const PlaneCase& pc : cases) {
      std::vector<uint8_t> want;
      for (uint64_t code : codes) {
        const Cell c = MortonDecode(code);
        const bool shadowed = InBox(c) ? c[2] < 4
                                       : c[0] >= pc.x0 && c[0] <= pc.x1 && c[1] >= pc.y0 && c[1] <= pc.y1;
        want.push_back(shadowed ? 1 : 0);
      }
      const Light light = MakeLight(pc.travel[0], pc.travel[1], pc.travel[2]);
      for (int threads : {1, 2, 3}) {
        ExpectSame(Shadows(dag, light, threads), want, codes,
                   "travel (" + std::to_string(pc.travel[0]) + ", " + std::to_string(pc.travel[1]) + ", " +
                       std::to_string(pc.travel[2]) + ") threads " + std::to_string(threads));
      }
    }
  }
}

TEST(ShadowedVoxels, LightFromBelowShadowsWhatLiesOverThePlane) {
  const std::vector<uint64_t> codes = BoxOnPlane();
  const Svdag dag = DagOf(codes, kPlaneDepth);
  std::vector<uint8_t> want;
  for (uint64_t code : codes) want.push_back(InBox(MortonDecode(code)) ? 1 : 0);
  ExpectSame(Shadows(dag, MakeLight(0, 0, 1)), want, codes, "travel +z");
}

// With (1, 0, -1) a plane voxel's ray passes exactly through the top edge of its -x neighbour, and
// closed cubes make that a shadow; such ties are checked against the definition (brute force),
// and the first two plane voxels of a row by hand.
TEST(ShadowedVoxels, GrazingEdgesAgreeWithBruteForce) {
  const std::vector<uint64_t> codes = BoxOnPlane();
  const Svdag dag = DagOf(codes, kPlaneDepth);
  for (auto t : {std::array<double, 3>{1, 0, -1}, {1, 1, -1}, {-1, 1, -1}, {1, 1, 0}, {1, 0, 0}}) {
    const Light light = MakeLight(t[0], t[1], t[2]);
    ExpectSame(Shadows(dag, light), BruteForceShadows(codes, light), codes, "grazing light");
  }
  // The plane voxel at x = 0 has no -x neighbour whose top edge it grazes; x = 1 has.
  const auto diagonal = Shadows(dag, MakeLight(1, 0, -1));
  for (size_t i = 0; i < codes.size(); ++i) {
    const Cell c = MortonDecode(codes[i]);
    if (c[2] == 0 && c[1] == 0 && c[0] <= 1) {
      EXPECT_EQ(diagonal[i], c[0] == 1 ? 1 : 0) << c[0];
    }
  }
}

// The definition's consequence for flat ground: a voxel's ray leaves its cell through a side face
// (into the neighbour) when the light is lower than 45 degrees along an axis, through the top when
// higher. So a one-voxel plane is self-shadowed except its first column below 45 degrees, and lit above.
TEST(ShadowedVoxels, FlatGroundShadowsItselfBelowFortyFiveDegrees) {
  std::vector<uint64_t> codes;
  for (uint32_t x = 0; x < 32; ++x) {
    for (uint32_t y = 0; y < 32; ++y) codes.push_back(MortonEncode(x, y, 0));
  }
  std::sort(codes.begin(), codes.end());
  const Svdag dag = DagOf(codes, kPlaneDepth);
  const double pi = std::acos(-1.0);
  for (double degrees : {40.0, 50.0}) {
    const double e = degrees * pi / 180;
    const Light light = MakeLight(std::cos(e), 0, -std::sin(e));  // travels +x: rays run to -x
    std::vector<uint8_t> want;
    for (uint64_t code : codes) want.push_back(degrees < 45 && MortonDecode(code)[0] > 0 ? 1 : 0);
    ExpectSame(Shadows(dag, light), want, codes, "elevation " + std::to_string(degrees));
  }
}

// ---------------------------------------------------------------------------------------------
// Brute force on random clutter (no data needed) and on real scans.

TEST(ShadowedVoxels, RandomClutterAgreesWithBruteForce) {
  std::mt19937 rng(16);
  std::uniform_int_distribution<uint32_t> coord(0, 15);
  std::vector<uint64_t> codes;
  for (int i = 0; i < 1200; ++i) codes.push_back(MortonEncode(coord(rng), coord(rng), coord(rng)));
  std::sort(codes.begin(), codes.end());
  codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
  std::normal_distribution<double> gauss;
  // Besides grazing diagonals: components so small that their inverses overflow to infinity.
  std::vector<std::array<double, 3>> directions = {{0, 0, -1}, {1, 1, -1}, {-1, 1, 1}, {1, 2, -2}, {0, 1, 0},
                                                   {1e-320, -1e-310, -1}, {1, 1e-300, 1e-300}};
  for (int i = 0; i < 6; ++i) directions.push_back({gauss(rng), gauss(rng), gauss(rng)});
  // The same voxels in a 16^3 grid, in a corner of a 64^3 one (more levels above), and in the far
  // corner of a 2^21 grid, where coordinates near 2^21 test the slab test's rounding margin.
  for (int depth : {4, 6, kMaxDepth}) {
    const uint32_t shift = depth == kMaxDepth ? (1u << depth) - 16 : 0;
    std::vector<uint64_t> placed;
    for (uint64_t code : codes) {
      const Cell c = MortonDecode(code);
      placed.push_back(MortonEncode(c[0] + shift, c[1] + shift, c[2] + shift));
    }
    std::sort(placed.begin(), placed.end());
    const Svdag dag = DagOf(placed, depth);
    for (const auto& d : directions) {
      const Light light = MakeLight(d[0], d[1], d[2]);
      ExpectSame(Shadows(dag, light), BruteForceShadows(placed, light), placed, "clutter depth " + std::to_string(depth));
    }
  }
}

struct ScanAtDepth {
  const char* file;
  int depth;
};

class ScanShadows : public ::testing::TestWithParam<ScanAtDepth> {};

TEST_P(ScanShadows, AgreeWithBruteForceOnEveryVoxel) {
  SKIP_WITHOUT_DATA();
  auto reader = OpenScan(testing::DataDir() / GetParam().file);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  VoxelizeOptions options;
  options.depth = GetParam().depth;
  auto grid = Voxelize(**reader, options);
  ASSERT_TRUE(grid.ok()) << grid.status().ToString();
  const std::vector<uint64_t>& codes = grid->morton;
  ASSERT_GT(codes.size(), 500u);
  const Svdag dag = DagOf(codes, grid->depth);
  std::mt19937 rng(GetParam().depth);
  std::normal_distribution<double> gauss;
  std::vector<std::array<double, 3>> directions = {{0, 0, -1}, {1, 1, -1}, {-1, 1, -1}, {1, 0, -1}, {0.3, -0.2, -0.93}};
  for (int i = 0; i < 3; ++i) directions.push_back({gauss(rng), gauss(rng), -std::fabs(gauss(rng))});
  size_t shadowed_total = 0;
  for (const auto& d : directions) {
    const Light light = MakeLight(d[0], d[1], d[2]);
    const auto got = Shadows(dag, light, 2);
    ExpectSame(got, BruteForceShadows(codes, light), codes,
               "direction (" + std::to_string(d[0]) + ", " + std::to_string(d[1]) + ", " + std::to_string(d[2]) + ")");
    for (uint8_t s : got) shadowed_total += s;
  }
  // A mipmap-mode DAG of the same voxels: the same answers in the same (Morton) order.
  const Svdag mip = DagOf(codes, grid->depth, CountMode::kMipmap);
  const Light sun = MakeLight(directions.back()[0], directions.back()[1], directions.back()[2]);
  EXPECT_EQ(Shadows(mip, sun), Shadows(dag, sun));
  // Real geometry: some voxels lit, some shadowed.
  EXPECT_GT(shadowed_total, 0u);
  EXPECT_LT(shadowed_total, codes.size() * directions.size());
}

INSTANTIATE_TEST_SUITE_P(Scans, ScanShadows,
                         ::testing::Values(ScanAtDepth{"lion_takanawa_pdrf7_rgb.las", 6},
                                           ScanAtDepth{"pcx_guanyin_cc-by-4.0_rgb.ply", 6},
                                           ScanAtDepth{"autzen_trim_pdrf3_rgb.las", 7}),
                         testing::ScanFileName());

// ---------------------------------------------------------------------------------------------
// Edge cases and sun hours.

TEST(ShadowedVoxels, OneVoxelIsLitFromEverywhere) {
  const std::vector<uint64_t> codes = {MortonEncode(1, 2, 3)};
  const Svdag dag = DagOf(codes, 2);
  for (auto t : {std::array<double, 3>{0, 0, -1}, {0, 0, 1}, {1, 1, -1}, {-0.2, 0.7, 0.1}}) {
    EXPECT_EQ(Shadows(dag, MakeLight(t[0], t[1], t[2])), std::vector<uint8_t>{0});
  }
}

TEST(ShadowedVoxels, BelowHorizonShadowsEverythingAndBadLightsAreRefused) {
  const std::vector<uint64_t> codes = BoxOnPlane();
  const Svdag dag = DagOf(codes, kPlaneDepth);
  Light night;
  night.below_horizon = true;
  EXPECT_EQ(Shadows(dag, night), std::vector<uint8_t>(codes.size(), 1));
  for (auto t : {std::array<double, 3>{NAN, 0, -1}, {0, 0, 0}, {0, -INFINITY, 0}}) {
    Light bad;
    bad.travel = t;
    auto shadowed = ShadowedVoxels(dag, bad);
    ASSERT_FALSE(shadowed.ok());
    EXPECT_EQ(shadowed.status().code(), StatusCode::kInvalidArgument);
    auto counts = LitSampleCounts(dag, std::vector<Light>{MakeLight(0, 0, -1), bad});
    ASSERT_FALSE(counts.ok());
    EXPECT_EQ(counts.status().code(), StatusCode::kInvalidArgument);
  }
  Svdag too_deep = dag;
  too_deep.depth = 22;
  auto refused = ShadowedVoxels(too_deep, MakeLight(0, 0, -1));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
}

TEST(LitSampleCounts, IsTheSumOfLitAnswers) {
  const std::vector<uint64_t> codes = BoxOnPlane();
  const Svdag dag = DagOf(codes, kPlaneDepth);
  std::vector<Light> lights;
  for (int i = 0; i < 8; ++i) {
    const double a = i * 0.7;
    lights.push_back(MakeLight(std::cos(a), std::sin(a), -0.4 - 0.1 * i));
  }
  Light night;
  night.below_horizon = true;
  lights.push_back(night);
  std::vector<uint16_t> want(codes.size(), 0);
  for (const Light& light : lights) {
    const auto shadowed = Shadows(dag, light);
    for (size_t i = 0; i < want.size(); ++i) want[i] = static_cast<uint16_t>(want[i] + (shadowed[i] ? 0 : 1));
  }
  auto counts = LitSampleCounts(dag, lights);
  ASSERT_TRUE(counts.ok()) << counts.status().ToString();
  EXPECT_EQ(*counts, want);
  EXPECT_GT(*std::max_element(want.begin(), want.end()), 0);
  EXPECT_LT(*std::min_element(want.begin(), want.end()), 8);
}

TEST(LitSampleCounts, CountsUpTo65535LightsAndRefusesMore) {
  const Svdag dag = DagOf({MortonEncode(0, 0, 0)}, 2);
  std::vector<Light> lights(65535, MakeLight(0, 0, -1));
  auto counts = LitSampleCounts(dag, lights, 1);
  ASSERT_TRUE(counts.ok()) << counts.status().ToString();
  EXPECT_EQ(*counts, std::vector<uint16_t>{65535});
  lights.push_back(lights.back());
  auto refused = LitSampleCounts(dag, lights);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace pointdag
