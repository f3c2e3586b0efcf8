// The light-space shadow DAG (shadow_dag.h) against the exact per-voxel shadows (voxel_shadows.h) on
// real scans and an analytic box on a plane; its byte form against hostile input.
#include "pointdag/shadow/shadow_dag.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <tuple>

#include "test_util.h"
#include "pointdag/container/crc32c.h"
#include "pointdag/dag/dag_builder.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/shadow/light_frame.h"
#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/voxelize/morton.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {
namespace {

Light Towards(double x, double y, double z) {
  const double n = std::sqrt(x * x + y * y + z * z);
  return Light{{x / n, y / n, z / n}, false};
}

Svdag DagOf(std::vector<uint64_t> codes, int depth) {
  std::sort(codes.begin(), codes.end());
  codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
  return BuildDag(codes, depth).value();
}

Svdag ScanDag(const std::string& name, int depth) {
  auto reader = OpenScan(testing::DataDir() / name);
  EXPECT_TRUE(reader.ok()) << reader.status().ToString();
  VoxelizeOptions options;
  options.depth = depth;
  auto grid = Voxelize(**reader, options);
  EXPECT_TRUE(grid.ok()) << grid.status().ToString();
  return BuildDag(grid->morton, grid->depth).value();
}

std::array<double, 3> Centre(uint64_t morton) {
  const auto [x, y, z] = MortonDecode(morton);
  return {x + 0.5, y + 0.5, z + 0.5};
}

// The DAG's answer at every voxel centre; the number of voxels where it differs from `exact`.
size_t Mismatches(const ShadowDag& shadow, const Svdag& dag, const std::vector<uint8_t>& exact) {
  size_t i = 0, wrong = 0;
  dag.ForEachVoxel([&](uint64_t morton) { wrong += shadow.Shadowed(Centre(morton)) != (exact[i++] != 0); });
  return wrong;
}

const std::vector<Light> kDirections = {Towards(0, 0, -1), Towards(1, 0.5, -1), Towards(-0.3, 0.8, -0.4),
                                        Towards(0.2, -0.1, -3), Towards(1, 1, 0.2)};

// Plane z = 0 of 16x16 voxels, a 4x4x4 box on it at (4..7, 4..7, 1..4).
Svdag BoxOnPlane() {
  std::vector<uint64_t> codes;
  for (uint32_t x = 0; x < 16; ++x) {
    for (uint32_t y = 0; y < 16; ++y) {
      codes.push_back(MortonEncode(x, y, 0));
      for (uint32_t z = 1; z <= 4 && x >= 4 && x < 8 && y >= 4 && y < 8; ++z) codes.push_back(MortonEncode(x, y, z));
    }
  }
  return DagOf(codes, 4);
}

TEST(ShadowDag, BoxOnPlaneMatchesTheAnalyticShadow) {
  const Svdag dag = BoxOnPlane();
  // Travelling (1, 0, -2): a plane voxel is shadowed behind the box up to x <= 4 + 4 - 1 + 4/2
  // (its ray enters the box's height at x + 0.25, leaves it at x + 0.25 - 2: no grazing ties);
  // a box voxel is shadowed by the one above it, the top layer is lit.
  for (const bool relax : {false, true}) {
    ShadowBuildOptions options;
    options.relax_undefined = relax;
    auto shadow = BuildShadowDag(dag, Towards(1, 0, -2), options);
    ASSERT_TRUE(shadow.ok()) << shadow.status().ToString();
    uint64_t shadowed = 0;
    dag.ForEachVoxel([&](uint64_t morton) {
      const auto [x, y, z] = MortonDecode(morton);
      const bool expected = z == 0 ? (y >= 4 && y < 8 && x >= 4 && x <= 9) : z < 4;
      shadowed += expected;
      EXPECT_EQ(shadow->Shadowed(Centre(morton)), expected) << x << "," << y << "," << z << " relax " << relax;
    });
    EXPECT_EQ(shadow->stats().shadowed_voxels, shadowed);
    EXPECT_EQ(shadow->stats().surface_voxels, dag.VoxelCount());
    EXPECT_EQ(shadow->stats().light_depth, 6);
    EXPECT_EQ(shadow->stats().dense_grid_bytes, uint64_t{1} << 15);
    EXPECT_EQ(shadow->stats().shadow_map_bytes, uint64_t{4} << 12);
    EXPECT_GT(shadow->stats().shadow_dag_bytes, 0u);
  }
  // Straight down: exactly the plane under the box and the box below its top.
  auto down = BuildShadowDag(dag, Towards(0, 0, -1));
  ASSERT_TRUE(down.ok());
  dag.ForEachVoxel([&](uint64_t morton) {
    const auto [x, y, z] = MortonDecode(morton);
    EXPECT_EQ(down->Shadowed(Centre(morton)), (x >= 4 && x < 8 && y >= 4 && y < 8 && z < 4) || (z > 0 && z < 4));
  });
}

TEST(ShadowDag, BelowTheHorizonEverythingIsShadowed) {
  const Svdag dag = BoxOnPlane();
  Light night = Towards(0.3, 0.2, 1);
  night.below_horizon = true;
  auto shadow = BuildShadowDag(dag, night);
  ASSERT_TRUE(shadow.ok()) << shadow.status().ToString();
  EXPECT_EQ(shadow->stats().shadowed_voxels, dag.VoxelCount());
  EXPECT_TRUE(shadow->Shadowed({0.5, 0.5, 0.5}));
  EXPECT_TRUE(shadow->Shadowed({15.5, 15.5, 15.5}));
  auto again = ShadowDag::Deserialize(shadow->Serialize());
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_TRUE(again->Shadowed({3.5, 9.5, 0.5}));
  night.travel = {std::nan(""), 0, 0};  // no direction at night is still night
  auto nan_night = BuildShadowDag(dag, night);
  ASSERT_TRUE(nan_night.ok()) << nan_night.status().ToString();
  EXPECT_TRUE(nan_night->Shadowed({4.5, 4.5, 2.5}));
}

TEST(ShadowDag, RefusesBadOptionsAndLights) {
  const Svdag dag = BoxOnPlane();
  ShadowBuildOptions options;
  options.extra_levels = 1;  // cells wide enough to hold two voxel centres
  EXPECT_EQ(BuildShadowDag(dag, Towards(0, 0, -1), options).status().code(), StatusCode::kInvalidArgument);
  const Light nan{{std::nan(""), 0, -1}, false};
  EXPECT_EQ(BuildShadowDag(dag, nan, {}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildShadowDag(dag, Light{{0, 0, 0}, false}, {}).status().code(), StatusCode::kInvalidArgument);
}

TEST(ShadowDag, LightDepthLimits) {
  // Two voxels on a depth-19 grid: light depth 21, the deepest; its dense grid is 2^60 bytes, exactly.
  const Svdag deep = DagOf({MortonEncode(5, 5, 5), MortonEncode(5, 5, 9)}, 19);
  auto shadow = BuildShadowDag(deep, Towards(0, 0, -1));
  ASSERT_TRUE(shadow.ok()) << shadow.status().ToString();
  EXPECT_EQ(shadow->stats().light_depth, 21);
  EXPECT_EQ(shadow->stats().dense_grid_bytes, uint64_t{1} << 60);
  EXPECT_EQ(shadow->stats().shadow_map_bytes, uint64_t{4} << 42);
  EXPECT_TRUE(shadow->Shadowed({5.5, 5.5, 5.5}));
  EXPECT_FALSE(shadow->Shadowed({5.5, 5.5, 9.5}));
  ASSERT_TRUE(ShadowDag::Deserialize(shadow->Serialize()).ok());
  ShadowBuildOptions options;
  options.extra_levels = 3;  // light depth 22: more than 63-bit codes hold
  EXPECT_EQ(BuildShadowDag(deep, Towards(0, 0, -1), options).status().code(), StatusCode::kInvalidArgument);
  options.extra_levels = 9;
  EXPECT_EQ(BuildShadowDag(BoxOnPlane(), Towards(0, 0, -1), options).status().code(), StatusCode::kInvalidArgument);
  // Finer light grids than needed answer the same.
  const Svdag box = BoxOnPlane();
  const Light light = Towards(0.7, -0.2, -1);
  const auto exact = ShadowedVoxels(box, light).value();
  for (int extra : {3, 5, 8}) {
    options.extra_levels = extra;
    auto fine = BuildShadowDag(box, light, options);
    ASSERT_TRUE(fine.ok()) << fine.status().ToString();
    EXPECT_EQ(fine->stats().light_depth, 4 + extra);
    EXPECT_EQ(Mismatches(*fine, box, exact), 0u) << extra;
  }
}

// With free space defined, a cell whose centre is outside every cube answers the definition's ray
// test from that centre; voxel centres stay exact.
TEST(ShadowDag, FreeSpaceAnswersTheAirToo) {
  std::vector<std::pair<Svdag, Light>> cases = {{BoxOnPlane(), Towards(1, 0.3, -2)}, {BoxOnPlane(), Towards(0, 0, -1)},
                                                {BoxOnPlane(), Towards(-0.4, 0.9, -0.5)}};
  if (std::filesystem::exists(testing::DataDir() / "tiny_1.2-with-color_1065pts.las")) {
    cases.emplace_back(ScanDag("pcl_milk_cartoon_clorox_kinect_rgb.ply", 5), Towards(0.3, 0.5, -0.8));
  }
  int shadowed_air = 0;
  for (const auto& [dag, light] : cases) {
    ShadowBuildOptions options;
    options.define_free_space = true;
    auto shadow = BuildShadowDag(dag, light, options);
    ASSERT_TRUE(shadow.ok()) << shadow.status().ToString();
    EXPECT_EQ(Mismatches(*shadow, dag, ShadowedVoxels(dag, light).value()), 0u);
    const auto frame = LightFrame::Create(light.travel, dag.depth, dag.depth + 2).value();
    const std::array<double, 3> travel = light.travel;  // clang 14 cannot capture a structured binding
    std::vector<std::array<uint32_t, 3>> voxels;
    dag.ForEachVoxel([&](uint64_t morton) { voxels.push_back(MortonDecode(morton)); });
    std::mt19937 rng(3);
    const double grid = std::ldexp(1.0, dag.depth);
    std::uniform_real_distribution<double> across(0, grid), low(0, grid / 2);
    int air = 0;
    for (int i = 0; i < 3000; ++i) {
      // The centre of the cell of a random point in the lower half of the grid, where shadows fall.
      const auto cell = frame.Cell({across(rng), across(rng), low(rng)});
      ASSERT_TRUE(cell.has_value());
      const auto p = frame.GridPoint({((*cell)[0] + 0.5) * frame.cell_size(), ((*cell)[1] + 0.5) * frame.cell_size(),
                                      ((*cell)[2] + 0.5) * frame.cell_size()});
      const auto inside = [&](const std::array<uint32_t, 3>& k) {
        return p[0] >= k[0] && p[0] <= k[0] + 1.0 && p[1] >= k[1] && p[1] <= k[1] + 1.0 && p[2] >= k[2] && p[2] <= k[2] + 1.0;
      };
      if (std::any_of(voxels.begin(), voxels.end(), inside)) continue;  // undefined
      const bool expected = std::any_of(voxels.begin(), voxels.end(), [&](const auto& k) { return RayMeetsCell(p, travel, k); });
      if (p[0] < 0 || p[1] < 0 || p[2] < 0 || p[0] > grid || p[1] > grid || p[2] > grid) continue;  // outside the grid
      ++air;
      shadowed_air += expected;
      EXPECT_EQ(shadow->Shadowed(p), expected) << p[0] << "," << p[1] << "," << p[2];
    }
    EXPECT_GT(air, 1000);
    // Surface-only is smaller: free space adds the shadow volumes' boundaries.
    auto surface = BuildShadowDag(dag, light);
    EXPECT_LT(surface->stats().shadow_dag_bytes, shadow->stats().shadow_dag_bytes);
    EXPECT_TRUE(ShadowDag::Deserialize(shadow->Serialize()).ok());
  }
  // The air behind the box (163 cells of the three box cases) and the scan, not only lit air; without
  // the shared scans only the box cases run.
  EXPECT_GT(shadowed_air, cases.size() > 3 ? 300 : 120);
}

// Every surface voxel of real scans at low resolution, several directions, each relaxation step
// and a collision-prone hash: the DAG answers what ShadowedVoxels answers.
TEST(ShadowDag, RealScansAgreeWithTheExactShadowsEverywhere) {
  SKIP_WITHOUT_DATA();
  for (const auto& [name, depth] : std::vector<std::pair<std::string, int>>{
           {"tiny_1.2-with-color_1065pts.las", 6}, {"lion_takanawa_pdrf7_rgb.las", 8},
           {"pcl_milk_cartoon_clorox_kinect_rgb.ply", 7}, {"ign_lidarhd_870000_6618000_pdrf8_rgb_epsg2154.las", 7},
           {"pcx_guanyin_cc-by-4.0_rgb.ply", 7}, {"autzen_trim_pdrf3_rgb.las", 7}, {"lone_star_tls_noRGB.las", 7}}) {
    const Svdag dag = ScanDag(name, depth);
    for (const Light& light : kDirections) {
      const auto exact = ShadowedVoxels(dag, light);
      ASSERT_TRUE(exact.ok()) << exact.status().ToString();
      std::vector<uint64_t> sizes;
      for (const auto& [relax, fill, free_space] :
           {std::tuple{false, UndefinedFill::kLit, false}, {true, UndefinedFill::kLit, false},
            {true, UndefinedFill::kMajority, false}, {true, UndefinedFill::kMatch, false}, {true, UndefinedFill::kMajority, true}}) {
        ShadowBuildOptions options;
        options.relax_undefined = relax;
        options.fill = fill;
        options.define_free_space = free_space;
        auto shadow = BuildShadowDag(dag, light, options);
        ASSERT_TRUE(shadow.ok()) << shadow.status().ToString();
        EXPECT_EQ(Mismatches(*shadow, dag, *exact), 0u) << name << " relax " << relax << " fill " << int(fill) << " free " << free_space;
        EXPECT_EQ(shadow->stats().shadowed_voxels, static_cast<uint64_t>(std::count(exact->begin(), exact->end(), 1)));
        sizes.push_back(shadow->stats().shadow_dag_bytes);

        options.hash_mask = 0x7;  // eight hash values: nearly every lookup collides
        auto narrow = BuildShadowDag(dag, light, options);
        ASSERT_TRUE(narrow.ok());
        EXPECT_EQ(Mismatches(*narrow, dag, *exact), 0u) << name << " narrow hash";
        // Collisions are confirmed by comparison, so the narrow hash merges exactly the same.
        EXPECT_EQ(narrow->stats().shadow_dag_bytes, shadow->stats().shadow_dag_bytes) << name;
      }
      // Collapsing undefined cells never grows the DAG.
      EXPECT_LE(sizes[1], sizes[0]) << name;
    }
  }
}

// Size regression (as zstd's): these bytes change only with a deliberate change of the build or its
// relaxation; update them in the same commit and say why.
TEST(ShadowDag, SizesOfAutzenAtDepth8AreKnown) {
  SKIP_WITHOUT_DATA();
  const Svdag dag = ScanDag("autzen_trim_pdrf3_rgb.las", 8);
  const Light sun = Towards(0.5, 0.5, -std::sqrt(0.5));
  ShadowBuildOptions unrelaxed;
  unrelaxed.relax_undefined = false;
  auto relaxed = BuildShadowDag(dag, sun), plain = BuildShadowDag(dag, sun, unrelaxed);
  ASSERT_TRUE(relaxed.ok() && plain.ok());
  EXPECT_EQ(relaxed->stats().shadowed_voxels, 14795u);
  EXPECT_EQ(relaxed->stats().shadow_dag_bytes, 21004u);  // docs/benchmarks.md: 20.5 KiB
  EXPECT_EQ(plain->stats().shadow_dag_bytes, 64212u);    // 62.7 KiB
}

TEST(ShadowDag, SerializedFormAnswersTheSame) {
  SKIP_WITHOUT_DATA();
  const Svdag dag = ScanDag("lion_takanawa_pdrf7_rgb.las", 7);
  const Light light = Towards(0.4, -0.7, -0.6);
  auto shadow = BuildShadowDag(dag, light);
  ASSERT_TRUE(shadow.ok());
  const std::vector<uint8_t> bytes = shadow->Serialize();
  EXPECT_EQ(bytes.size(), 64 + shadow->stats().shadow_dag_bytes);
  auto back = ShadowDag::Deserialize(bytes);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->Serialize(), bytes);
  EXPECT_EQ(back->stats().surface_voxels, shadow->stats().surface_voxels);
  EXPECT_EQ(back->stats().shadowed_voxels, shadow->stats().shadowed_voxels);
  EXPECT_EQ(back->stats().shadow_dag_bytes, shadow->stats().shadow_dag_bytes);
  EXPECT_EQ(back->stats().light_depth, shadow->stats().light_depth);
  EXPECT_EQ(Mismatches(*back, dag, ShadowedVoxels(dag, light).value()), 0u);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> any(-10, 140);
  for (int i = 0; i < 20000; ++i) {
    const std::array<double, 3> p{any(rng), any(rng), any(rng)};
    ASSERT_EQ(back->Shadowed(p), shadow->Shadowed(p)) << p[0] << "," << p[1] << "," << p[2];
  }
  EXPECT_FALSE(back->Shadowed({std::nan(""), 1, 1}));
}

// The spec's layout, written by hand (fuzz/seeds/shadow_dag/two_levels.bin): depth 2, light depth 4,
// light straight down, so x' = x, y' = -y, z' = -z and cell i = floor(4·(x, 4 - y, 4 - z)). The root
// sends octant 0 to a record whose octant 0 is leaf 0b101 (cells (0,0,0) and (0,1,0) shadowed) and
// stores octant 7 (x >= 2, y <= 2, z <= 2) as all shadowed.
TEST(ShadowDag, ReadsTheSpecExample) {
  const std::string hex =
      "504453440100020400000000000000000000000000000000000000000000f0bf0200000004000000010000000300000000000000"
      "010000000000000078d36169018000000200000001000000000000000500000000000000";
  std::vector<uint8_t> bytes;
  for (size_t i = 0; i < hex.size(); i += 2) bytes.push_back(static_cast<uint8_t>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  auto dag = ShadowDag::Deserialize(bytes);
  ASSERT_TRUE(dag.ok()) << dag.status().ToString();
  EXPECT_TRUE(dag->Shadowed({0.1, 3.9, 3.9}));   // cell (0,0,0)
  EXPECT_TRUE(dag->Shadowed({0.1, 3.7, 3.9}));   // cell (0,1,0)
  EXPECT_FALSE(dag->Shadowed({0.3, 3.9, 3.9}));  // cell (1,0,0)
  EXPECT_TRUE(dag->Shadowed({3, 1, 1}));         // octant 7
  EXPECT_FALSE(dag->Shadowed({1.5, 1.5, 1.5}));  // octant 3: all lit
  EXPECT_FALSE(dag->Shadowed({3, 1, 5}));        // outside the light cube
  EXPECT_EQ(dag->stats().surface_voxels, 3u);
  EXPECT_EQ(dag->stats().shadowed_voxels, 1u);
  EXPECT_EQ(dag->stats().shadow_dag_bytes, 4u * 4 + 8);
  EXPECT_EQ(dag->Serialize(), bytes);
}

// The fuzz seeds were written from the spec alone (a Python script); all of them must read.
TEST(ShadowDag, ReadsEveryFuzzSeed) {
  const auto dir = std::filesystem::path(POINTDAG_SOURCE_DIR) / "fuzz" / "seeds" / "shadow_dag";
  int seen = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const auto dag = ShadowDag::Deserialize(testing::ReadBytes(entry.path()));
    EXPECT_TRUE(dag.ok()) << entry.path() << ": " << dag.status().ToString();
    ++seen;
  }
  EXPECT_GE(seen, 4);
}

// Hostile bytes: every corruption is a typed error, never a crash.
class HostileShadowBytes : public ::testing::Test {
 protected:
  void SetUp() override {
    auto shadow = BuildShadowDag(BoxOnPlane(), Towards(1, 0.3, -2));
    ASSERT_TRUE(shadow.ok());
    good_ = shadow->Serialize();
    words_ = LoadWord(36);
    leaves_ = LoadWord(40);
    ASSERT_GT(words_, 4u);
    ASSERT_GT(leaves_, 1u);
  }
  uint32_t LoadWord(size_t at) const {
    uint32_t v;
    std::memcpy(&v, good_.data() + at, 4);
    return v;
  }
  // The bytes with one word changed and the CRC made right again, so the structure checks see it.
  static std::vector<uint8_t> WithWord(std::vector<uint8_t> b, size_t at, uint32_t value) {
    std::memcpy(b.data() + at, &value, 4);
    const uint32_t crc = Crc32c(std::span<const uint8_t>(b).subspan(64), Crc32c(std::span<const uint8_t>(b).first(60)));
    std::memcpy(b.data() + 60, &crc, 4);
    return b;
  }
  static StatusCode Code(const std::vector<uint8_t>& b) { return ShadowDag::Deserialize(b).status().code(); }

  std::vector<uint8_t> good_;
  uint32_t words_ = 0, leaves_ = 0;
};

TEST_F(HostileShadowBytes, TruncatedAtEveryLength) {
  ASSERT_TRUE(ShadowDag::Deserialize(good_).ok());
  for (size_t n = 0; n < good_.size(); ++n) {
    const auto code = Code(std::vector<uint8_t>(good_.begin(), good_.begin() + static_cast<long>(n)));
    EXPECT_TRUE(code == StatusCode::kTruncated) << n;
  }
  auto longer = good_;
  longer.push_back(0);
  EXPECT_EQ(Code(WithWord(longer, 0, 0x44534450)), StatusCode::kMalformed);
}

TEST_F(HostileShadowBytes, HeaderLies) {
  EXPECT_EQ(Code(WithWord(good_, 0, 0x12345678)), StatusCode::kCorrupt);                   // magic
  EXPECT_EQ(Code(WithWord(good_, 4, LoadWord(4) ^ 0x3)), StatusCode::kUnsupported);      // version 2
  EXPECT_EQ(Code(WithWord(good_, 36, words_ + 1)), StatusCode::kTruncated);               // node count too big
  EXPECT_EQ(Code(WithWord(good_, 36, words_ - 2)), StatusCode::kMalformed);               // too small: trailing bytes
  EXPECT_EQ(Code(WithWord(good_, 40, 0xFFFFFFFFu)), StatusCode::kTruncated);              // absurd leaf count
  auto flipped = good_;
  flipped[70] ^= 1;  // a node word changed, CRC not updated
  EXPECT_EQ(Code(flipped), StatusCode::kCorrupt);
  EXPECT_EQ(Code(WithWord(good_, 4, LoadWord(4) | 0x0200)), StatusCode::kMalformed);     // unknown flag
  EXPECT_EQ(Code(WithWord(good_, 4, (LoadWord(4) & 0xFF00FFFFu) | 30u << 16)), StatusCode::kMalformed);  // depth 30
  EXPECT_EQ(Code(WithWord(good_, 4, (LoadWord(4) & 0x00FFFFFFu) | 5u << 24)), StatusCode::kMalformed);   // light depth 5 < 4 + 2
  EXPECT_EQ(Code(WithWord(good_, 8, 0)), StatusCode::kOk);                                 // travel's low bits: still a direction
  EXPECT_EQ(Code(WithWord(WithWord(good_, 12, 0x7FF80000u), 8, 0)), StatusCode::kMalformed);  // travel.x NaN
  EXPECT_EQ(Code(WithWord(good_, 32, 7)), StatusCode::kMalformed);                          // root kind
  EXPECT_EQ(Code(WithWord(good_, 32, 1)), StatusCode::kMalformed);                          // all shadowed, yet nodes
  EXPECT_EQ(Code(WithWord(good_, 56, 1)), StatusCode::kMalformed);                          // shadowed > voxels
}

TEST_F(HostileShadowBytes, BadReferences) {
  // The root's first pointer: out of range, backwards onto itself (a cycle), into a pointer word.
  const uint32_t root = LoadWord(64);
  ASSERT_NE(root & 0xFF, 0u);
  EXPECT_EQ(Code(WithWord(good_, 68, words_ + 5)), StatusCode::kMalformed);
  EXPECT_EQ(Code(WithWord(good_, 68, 0)), StatusCode::kMalformed);
  EXPECT_EQ(Code(WithWord(good_, 68, 1)), StatusCode::kMalformed);
  // Root masks overlapping, bits above 16, an all-lit record, a record running past the end.
  EXPECT_EQ(Code(WithWord(good_, 64, root | (root & 0xFF) << 8)), StatusCode::kMalformed);
  EXPECT_EQ(Code(WithWord(good_, 64, root | 1u << 20)), StatusCode::kMalformed);
  EXPECT_EQ(Code(WithWord(good_, 64, 0)), StatusCode::kMalformed);
  EXPECT_EQ(Code(WithWord(good_, 64, 0xFF)), StatusCode::kMalformed);
  // Leaves: an all-lit leaf, an all-shadowed one; a leaf reference out of range (the last word
  // before the leaves belongs to the last internal level).
  const size_t first_leaf = 64 + size_t{words_} * 4;
  EXPECT_EQ(Code(WithWord(WithWord(good_, first_leaf, 0), first_leaf + 4, 0)), StatusCode::kMalformed);
  EXPECT_EQ(Code(WithWord(WithWord(good_, first_leaf, ~0u), first_leaf + 4, ~0u)), StatusCode::kMalformed);
  EXPECT_EQ(Code(WithWord(good_, first_leaf - 4, leaves_)), StatusCode::kMalformed);
  // Random words anywhere, CRC fixed: never a crash, and what decodes answers queries.
  std::mt19937 rng(16);
  for (int i = 0; i < 3000; ++i) {
    const size_t at = 32 + rng() % ((good_.size() - 36) / 4) * 4;
    if (at == 60) continue;
    auto dag = ShadowDag::Deserialize(WithWord(good_, at, static_cast<uint32_t>(rng())));
    if (dag.ok()) (void)dag->Shadowed({7.5, 5.5, 0.5});
  }
}

}  // namespace
}  // namespace pointdag
