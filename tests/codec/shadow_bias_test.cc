// The self-shadow bias (light.h, issue #16): occluders count only beyond `bias_voxels` of the
// voxel's centre. Brute force with the bias, flat ground against the analytic threshold
// 0.5 / sin(elevation), the shadow DAG and sun hours following it, and the refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "pointdag/dag/dag_builder.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/shadow/light.h"
#include "pointdag/shadow/shadow_dag.h"
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

Svdag DagOf(const std::vector<uint64_t>& sorted_codes, int depth) {
  auto dag = BuildDag(sorted_codes, depth);
  EXPECT_TRUE(dag.ok()) << dag.status().ToString();
  return std::move(dag.value());
}

Light BiasedLight(double x, double y, double z, double bias) {
  Light light = LightFromDirection(x, y, z).value();
  light.bias_voxels = bias;
  return light;
}

size_t Differences(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size());
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
  return n;
}

size_t Count(const std::vector<uint8_t>& v) { return static_cast<size_t>(std::count(v.begin(), v.end(), 1)); }

TEST(RayMeetsCell, BiasIgnoresTheNearPartOfTheRay) {
  const std::array<double, 3> down{0, 0, -1};  // rays go up; cell (0, 0, 2) spans t in [1.5, 2.5]
  EXPECT_TRUE(RayMeetsCell({0.5, 0.5, 0.5}, down, {0, 0, 2}, 2.4));
  EXPECT_FALSE(RayMeetsCell({0.5, 0.5, 0.5}, down, {0, 0, 2}, 2.5));  // t > bias, strictly
  EXPECT_TRUE(RayMeetsCell({0.5, 0.5, 0.5}, down, {0, 0, 1}, 0.5));   // [0.5, 1.5]
  EXPECT_FALSE(RayMeetsCell({0.5, 0.5, 0.5}, down, {0, 0, 1}, 1.5));
  EXPECT_EQ(RayMeetsCell({0.5, 0.5, 0.5}, down, {0, 0, 1}), RayMeetsCell({0.5, 0.5, 0.5}, down, {0, 0, 1}, 0.0));
}

// Flat ground, the light travelling +x at elevation e (rays run to -x and up). A ray stays inside
// the ground's layer up to t = 0.5 / sin e, so a bias of at least that leaves the ground lit; just
// below it, every voxel whose ray is still over the ground at that t (x + 0.5 >= 0.5 / tan e) is shadowed.
TEST(ShadowedVoxels, FlatGroundIsLitOnceTheBiasReachesHalfOverSinElevation) {
  std::vector<uint64_t> codes;
  for (uint32_t x = 0; x < 32; ++x) {
    for (uint32_t y = 0; y < 32; ++y) codes.push_back(MortonEncode(x, y, 0));
  }
  std::sort(codes.begin(), codes.end());
  const Svdag dag = DagOf(codes, 5);
  const double pi = std::acos(-1.0);
  for (double degrees : {10.0, 20.0, 30.0, 40.0}) {
    // At 30 degrees sin is 0.5 exactly (not sin() of a rounded angle), so the threshold is 1.0.
    const double sin_e = degrees == 30 ? 0.5 : std::sin(degrees * pi / 180);
    const double cos_e = std::sqrt(1 - sin_e * sin_e);
    const double threshold = 0.5 / sin_e;
    Light light;
    light.travel = {cos_e, 0, -sin_e};
    if (degrees == 30) {
      EXPECT_EQ(threshold, 1.0);
    }
    const std::string what = std::to_string(degrees) + " degrees";

    light.bias_voxels = threshold;
    EXPECT_EQ(Count(Shadows(dag, light)), 0u) << what;
    EXPECT_EQ(Differences(Shadows(dag, light), BruteForceShadows(codes, light)), 0u) << what;

    light.bias_voxels = std::nextafter(threshold, 0.0);
    const auto below = Shadows(dag, light);
    ASSERT_EQ(below.size(), codes.size());
    for (size_t i = 0; i < codes.size(); ++i) {
      const double x = MortonDecode(codes[i])[0] + 0.5;
      EXPECT_EQ(below[i], x >= 0.5 * cos_e / sin_e ? 1 : 0) << what << ", x " << x;
    }
    EXPECT_EQ(Differences(below, BruteForceShadows(codes, light)), 0u) << what;
  }
}

// Random clutter in a 16^3 grid, in a corner of a 64^3 one and in the far corner of a 2^21 one
// (the slab test's rounding), for several biases, against the brute force.
TEST(ShadowedVoxels, BiasedRaysAgreeWithBruteForceOnClutter) {
  std::mt19937 rng(1616);
  std::uniform_int_distribution<uint32_t> coord(0, 15);
  std::vector<Cell> cells;
  for (int i = 0; i < 1000; ++i) cells.push_back({coord(rng), coord(rng), coord(rng)});
  std::normal_distribution<double> gauss;
  std::vector<std::array<double, 3>> directions = {{0, 0, -1}, {1, 1, -1}, {1, 0, -1}, {-1, 2, -0.5}};
  for (int i = 0; i < 4; ++i) directions.push_back({gauss(rng), gauss(rng), gauss(rng)});
  for (int depth : {4, 6, kMaxDepth}) {
    const uint32_t shift = depth == kMaxDepth ? (1u << depth) - 16 : 0;
    std::vector<uint64_t> codes;
    for (const Cell& c : cells) codes.push_back(MortonEncode(c[0] + shift, c[1] + shift, c[2] + shift));
    std::sort(codes.begin(), codes.end());
    codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
    const Svdag dag = DagOf(codes, depth);
    for (const auto& d : directions) {
      std::vector<uint8_t> previous;
      for (double bias : {0.0, 0.25, 0.5, 1.0, std::sqrt(3.0), 3.0, 16.0}) {
        const Light light = BiasedLight(d[0], d[1], d[2], bias);
        const auto got = Shadows(dag, light);
        EXPECT_EQ(Differences(got, BruteForceShadows(codes, light)), 0u) << "depth " << depth << " bias " << bias;
        // A larger bias only ever ignores occluders.
        for (size_t i = 0; i < previous.size(); ++i) ASSERT_LE(got[i], previous[i]) << "bias " << bias;
        previous = got;
      }
    }
  }
}

// A real scan: brute force, the shadow DAG (whose defined cells are ShadowedVoxels' answers) and
// sun hours all follow the bias.
TEST(ShadowedVoxels, BiasOnARealScanReachesTheDagAndSunHours) {
  SKIP_WITHOUT_DATA();
  auto reader = OpenScan(testing::DataDir() / "autzen_trim_pdrf3_rgb.las");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  VoxelizeOptions options;
  options.depth = 7;
  auto grid = Voxelize(**reader, options);
  ASSERT_TRUE(grid.ok()) << grid.status().ToString();
  const std::vector<uint64_t>& codes = grid->morton;
  const Svdag dag = DagOf(codes, grid->depth);
  const double pi = std::acos(-1.0), e = 35 * pi / 180;  // a low sun from the south-east
  std::vector<Light> suns;
  for (double bias : {0.0, 1.0, 2.0}) {
    const Light light = BiasedLight(-std::cos(e) * std::sqrt(0.5), std::cos(e) * std::sqrt(0.5), -std::sin(e), bias);
    suns.push_back(light);
    const auto exact = Shadows(dag, light);
    EXPECT_EQ(Differences(exact, BruteForceShadows(codes, light)), 0u) << "bias " << bias;
    auto shadow_dag = BuildShadowDag(dag, light);
    ASSERT_TRUE(shadow_dag.ok()) << shadow_dag.status().ToString();
    EXPECT_EQ(shadow_dag->stats().shadowed_voxels, Count(exact));
    size_t i = 0, wrong = 0;
    for (uint64_t code : codes) {
      const Cell c = MortonDecode(code);
      wrong += shadow_dag->Shadowed({c[0] + 0.5, c[1] + 0.5, c[2] + 0.5}) != (exact[i++] != 0);
    }
    EXPECT_EQ(wrong, 0u) << "bias " << bias;
  }
  // The bias is what turns the self-shadowed ground lit (8,623 -> 4,383 of 8,993 voxels): 1 is
  // past 0.5 / sin 35 = 0.87, so 2 adds nothing on the ground.
  const size_t unbiased = Count(Shadows(dag, suns[0])), one = Count(Shadows(dag, suns[1]));
  EXPECT_LT(one, unbiased * 6 / 10);
  EXPECT_GE(one, Count(Shadows(dag, suns[2])));
  auto lit = LitSampleCounts(dag, suns, 2);
  ASSERT_TRUE(lit.ok());
  std::vector<uint16_t> want(codes.size(), 0);
  for (const Light& s : suns) {
    const auto shadowed = Shadows(dag, s);
    for (size_t i = 0; i < want.size(); ++i) want[i] = static_cast<uint16_t>(want[i] + (shadowed[i] ^ 1));
  }
  EXPECT_EQ(*lit, want);
}

TEST(ShadowedVoxels, BadBiasesAreRefusedEverywhere) {
  const std::vector<uint64_t> codes = {MortonEncode(0, 0, 0), MortonEncode(0, 0, 1)};
  const Svdag dag = DagOf(codes, 2);
  const double inf = std::numeric_limits<double>::infinity();
  for (double bias : {-0.001, std::nextafter(kMaxShadowBias, 17.0), std::nan(""), inf, -inf}) {
    Light light = BiasedLight(0, 0, -1, bias);
    EXPECT_EQ(CheckShadowBias(bias).code(), StatusCode::kInvalidArgument) << bias;
    EXPECT_EQ(ShadowedVoxels(dag, light).status().code(), StatusCode::kInvalidArgument) << bias;
    EXPECT_EQ(LitSampleCounts(dag, std::vector<Light>{light}).status().code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(BuildShadowDag(dag, light).status().code(), StatusCode::kInvalidArgument) << bias;
    light.below_horizon = true;  // even where no ray is cast
    EXPECT_EQ(ShadowedVoxels(dag, light).status().code(), StatusCode::kInvalidArgument) << bias;
  }
  for (double bias : {0.0, 16.0}) {
    EXPECT_TRUE(CheckShadowBias(bias).ok());
    EXPECT_EQ(Shadows(dag, BiasedLight(0, 0, -1, bias)), (std::vector<uint8_t>{bias == 0 ? uint8_t{1} : uint8_t{0}, 0}));
  }
}

}  // namespace
}  // namespace pointdag
