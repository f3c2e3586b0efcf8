#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "pointdag/read/memory_reader.h"
#include "pointdag/read/scan_reader.h"
#include "pointdag/voxelize/morton.h"
#include "pointdag/voxelize/point_spacing.h"
#include "pointdag/voxelize/radix_sort.h"
#include "pointdag/voxelize/voxelizer.h"
#include "test_util.h"

namespace pointdag {
namespace {

TEST(Morton, RoundTripsAndInterleavesXHighest) {
  EXPECT_EQ(MortonEncode(1, 0, 0), 4u);
  EXPECT_EQ(MortonEncode(0, 1, 0), 2u);
  EXPECT_EQ(MortonEncode(0, 0, 1), 1u);
  EXPECT_EQ(MortonEncode(2, 0, 0), 32u);
  const uint32_t max = (1u << 21) - 1;
  EXPECT_EQ(MortonEncode(max, max, max), (uint64_t{1} << 63) - 1);
  std::mt19937 rng(5);
  for (int i = 0; i < 10000; ++i) {
    const uint32_t x = rng() & max, y = rng() & max, z = rng() & max;
    EXPECT_EQ(MortonDecode(MortonEncode(x, y, z)), (std::array<uint32_t, 3>{x, y, z}));
  }
}

// The table-driven MortonEncode against the bit-spreading definition, high bits beyond 21 ignored.
TEST(Morton, TableMatchesSpreadBits) {
  std::mt19937 rng(7);
  for (int i = 0; i < 100000; ++i) {
    const auto x = static_cast<uint32_t>(rng()), y = static_cast<uint32_t>(rng()), z = static_cast<uint32_t>(rng());
    EXPECT_EQ(MortonEncode(x, y, z), SpreadBits3(x) << 2 | SpreadBits3(y) << 1 | SpreadBits3(z));
  }
}

StatusOr<VoxelGrid> VoxelizeInMemory(std::vector<std::array<double, 3>> xyz, std::vector<std::array<uint16_t, 3>> rgb,
                        VoxelizeOptions options) {
  MemoryScanReader reader(std::move(xyz), std::move(rgb));
  return Voxelize(reader, options);
}

// MedianPointSpacing's contract by brute force: every point's nearest other point, duplicates left out.
double BruteForceSpacing(const std::vector<std::array<double, 3>>& points) {
  std::vector<double> nearest;
  for (size_t i = 0; i < points.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < points.size(); ++j) {
      if (j == i) continue;
      const double dx = points[i][0] - points[j][0], dy = points[i][1] - points[j][1], dz = points[i][2] - points[j][2];
      best = std::min(best, dx * dx + dy * dy + dz * dz);
    }
    if (best > 0) nearest.push_back(best);
  }
  if (nearest.empty()) return 0;
  std::nth_element(nearest.begin(), nearest.begin() + static_cast<long>(nearest.size() / 2), nearest.end());
  return std::sqrt(nearest[nearest.size() / 2]);
}

// Shapes that stress the grid: its cells sized for surfaces, runs split over two threads (from
// 4,096 points), isolated points searched in further shells and by brute force, UTM-sized offsets.
TEST(PointSpacing, EqualsBruteForceOnSurfacesVolumesLinesDuplicatesAndOutliers) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> noise(0, 1);
  for (int shape = 0; shape < 8; ++shape) {
    SCOPED_TRACE(shape);
    std::vector<std::array<double, 3>> points;
    const size_t n = shape == 6 ? 40 : 5000;
    const double x0 = shape % 2 ? 870000.0 : 0.0, y0 = shape % 2 ? 6618000.0 : 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double u = unit(rng), v = unit(rng), w = unit(rng);
      switch (shape) {
        case 0: points.push_back({u, v, w}); break;                                               // a volume
        case 1: points.push_back({x0 + 500 * u, y0 + 500 * v, 30 + 0.05 * noise(rng)}); break;  // terrain
        case 2: points.push_back({std::round(40 * u) / 4, std::round(40 * v) / 4, 0}); break;   // a lattice: duplicates, ties
        case 3: points.push_back({x0 + 100 * u, y0 + 0.3 * u, 2.0}); break;                     // a line
        case 4:                                                                                   // a dense cluster, sparse far points
          points.push_back(i % 10 ? std::array<double, 3>{0.01 * u, 0.01 * v, 0.01 * w} : std::array<double, 3>{1000 * u, 1000 * v, 1000 * w});
          break;
        case 5:  // an outlier far from a cube
          points.push_back({x0 + u, y0 + v, w});
          if (i == 0) points.push_back({x0 + 1e4, y0 + 1e4, 1e4});
          break;
        case 6: points.push_back({std::floor(3 * u), 0, 0}); break;  // few points, in three places
        default: points.push_back({10 * u, 10 * v, std::floor(4 * w) * 0.37}); break;  // stacked planes
      }
    }
    EXPECT_EQ(MedianPointSpacing(points), BruteForceSpacing(points));
  }
  // Small clouds, where the median hangs on a few points' nearest neighbours: boxes of any aspect,
  // some points snapped to a coarse lattice (equal distances, duplicates).
  for (int trial = 0; trial < 400; ++trial) {
    SCOPED_TRACE(trial);
    const size_t n = 3 + rng() % 80;
    const std::array<double, 3> size = {std::exp(6 * unit(rng) - 3), std::exp(6 * unit(rng) - 3), std::exp(6 * unit(rng) - 3)};
    std::vector<std::array<double, 3>> points;
    for (size_t i = 0; i < n; ++i) {
      std::array<double, 3> p = {size[0] * unit(rng), size[1] * unit(rng), size[2] * unit(rng)};
      if (trial % 3 == 0) {
        for (double& x : p) x = std::round(x * 4) / 4;
      }
      points.push_back(p);
    }
    ASSERT_EQ(MedianPointSpacing(points), BruteForceSpacing(points));
  }
  EXPECT_EQ(MedianPointSpacing(std::vector<std::array<double, 3>>(5, {1, 2, 3})), 0.0);  // all coincide
  EXPECT_EQ(MedianPointSpacing(std::vector<std::array<double, 3>>{{1, 2, 3}}), 0.0);
  EXPECT_EQ(MedianPointSpacing(std::vector<std::array<double, 3>>{{0, 0, 0}, {3, 4, 0}}), 5.0);
}

TEST(Voxelizer, MergesPointsOfAVoxelWithTheirMeanColor) {
  VoxelizeOptions options;
  options.voxel_size = 1.0;
  // Bounds 0..3: depth 2 (4 cells per side). Two points share cell (0,0,0); one is in (3,3,3).
  auto grid = VoxelizeInMemory({{0.0, 0.2, 0.3}, {0.9, 0.0, 0.0}, {3.0, 3.0, 3.0}}, {{10, 20, 30}, {21, 40, 255}, {1, 2, 3}}, options);
  ASSERT_TRUE(grid.ok()) << grid.status().ToString();
  EXPECT_EQ(grid->depth, 2);
  EXPECT_EQ(grid->points_in, 3u);
  ASSERT_EQ(grid->morton.size(), 2u);
  EXPECT_EQ(grid->morton[0], MortonEncode(0, 0, 0));
  EXPECT_EQ(grid->morton[1], MortonEncode(3, 3, 3));
  EXPECT_EQ(grid->colors[0], (Rgb8{16, 30, 143}));  // (10+21)/2 = 15.5 -> 16; (30+255)/2 = 142.5 -> 143
  EXPECT_EQ(grid->colors[1], (Rgb8{1, 2, 3}));
  EXPECT_EQ(grid->VoxelCentre(grid->morton[1]), (std::array<double, 3>{3.5, 3.5, 3.5}));
}

TEST(Voxelizer, ScalesSixteenBitColorToEightBits) {
  VoxelizeOptions options;
  options.depth = 3;
  auto grid = VoxelizeInMemory({{0, 0, 0}, {1, 1, 1}}, {{65535, 257, 256 * 128}, {0, 0, 0}}, options);
  ASSERT_TRUE(grid.ok());
  EXPECT_EQ(grid->source_color_bits, 16);
  EXPECT_EQ(grid->colors[0], (Rgb8{255, 1, 128}));
}

TEST(Voxelizer, ScanWithoutColorGetsNoColor) {
  VoxelizeOptions options;
  options.depth = 4;
  auto grid = VoxelizeInMemory({{0, 0, 0}, {5, 5, 5}}, {}, options);
  ASSERT_TRUE(grid.ok());
  EXPECT_FALSE(grid->has_color());
}

TEST(Voxelizer, DepthFromVoxelSizeCoversTheExtent) {
  EXPECT_EQ(*DepthForVoxelSize(3.0, 1.0), 2);     // 4 cells
  EXPECT_EQ(*DepthForVoxelSize(4.0, 1.0), 3);     // the maximum at 4.0 needs a fifth cell
  EXPECT_EQ(*DepthForVoxelSize(1023.5, 1.0), 10);
  EXPECT_EQ(*DepthForVoxelSize(0.0, 1.0), 2);     // a single point still gets a 4^3 grid
  EXPECT_EQ(DepthForVoxelSize(1e7, 1.0).status().code(), StatusCode::kInvalidArgument);  // > 2^21 cells
  EXPECT_EQ(DepthForVoxelSize(1.0, 0.0).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(DepthForVoxelSize(1.0, std::nan("")).status().code(), StatusCode::kInvalidArgument);
}

TEST(Voxelizer, RejectsBadOptions) {
  VoxelizeOptions none;
  EXPECT_EQ(VoxelizeInMemory({{0, 0, 0}}, {}, none).status().code(), StatusCode::kInvalidArgument);
  VoxelizeOptions deep;
  deep.depth = 22;
  EXPECT_EQ(VoxelizeInMemory({{0, 0, 0}}, {}, deep).status().code(), StatusCode::kInvalidArgument);
  VoxelizeOptions shallow;
  shallow.depth = 1;
  EXPECT_EQ(VoxelizeInMemory({{0, 0, 0}}, {}, shallow).status().code(), StatusCode::kInvalidArgument);
}

TEST(Voxelizer, VoxelSizeAfterTheSurveyGivesTheSameGrid) {
  std::vector<std::array<double, 3>> xyz;
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> coord(0, 10);
  for (int i = 0; i < 5000; ++i) xyz.push_back({coord(rng), coord(rng), coord(rng)});
  VoxelizeOptions given;
  given.voxel_size = 0.5;
  VoxelizeOptions later;
  bool asked = false;
  later.voxel_size_after_survey = [&]() -> StatusOr<double> {
    asked = true;
    return 0.5;
  };
  const auto a = VoxelizeInMemory(xyz, {}, given), b = VoxelizeInMemory(xyz, {}, later);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(asked);
  EXPECT_EQ(a->morton, b->morton);
  EXPECT_EQ(a->depth, b->depth);
  later.voxel_size_after_survey = []() -> StatusOr<double> { return InvalidArgument("no spacing"); };
  EXPECT_EQ(VoxelizeInMemory(xyz, {}, later).status().code(), StatusCode::kInvalidArgument);
  later.voxel_size = 0.5;  // two sizes
  EXPECT_EQ(VoxelizeInMemory(xyz, {}, later).status().code(), StatusCode::kInvalidArgument);
}

TEST(RadixSort, SortsLikeStdSortWithDuplicatesAndEveryWidth) {
  std::mt19937_64 rng(3);
  for (int bits : {1, 7, 8, 9, 30, 63}) {
    // Sizes about the insertion sort's limit, the scratch buffer's (kRadixScratchItems) and past it
    // (in-place passes first, then the scratch sort on the parts).
    for (size_t n : {size_t{0}, size_t{1}, kInsertionItems, kInsertionItems + 1, size_t{64}, size_t{5000},
                     kRadixScratchItems, kRadixScratchItems + 1, size_t{100000}, size_t{300000}}) {
      std::vector<std::pair<uint64_t, uint32_t>> items(n);
      // Few distinct keys for some sizes: many duplicates, deep recursion on equal keys.
      const uint64_t mask = bits == 63 ? (uint64_t{1} << 63) - 1 : (uint64_t{1} << bits) - 1;
      const uint64_t few = n == 5000 ? 0xFFF0F0 : n == 300000 ? 0xF000000F : ~uint64_t{0};
      for (size_t i = 0; i < n; ++i) items[i] = {rng() & mask & few, static_cast<uint32_t>(i)};
      auto expected = items;
      std::sort(expected.begin(), expected.end());
      RadixSortInPlace(std::span(items), bits, [](const auto& item) { return item.first; });
      ASSERT_TRUE(std::is_sorted(items.begin(), items.end(), [](const auto& a, const auto& b) { return a.first < b.first; }));
      std::sort(items.begin(), items.end(), [](const auto& a, const auto& b) {
        return a.first != b.first ? a.first < b.first : a.second < b.second;
      });  // equal keys may come in any order: the same items?
      ASSERT_EQ(items, expected) << bits << " bits, " << n << " items";
    }
  }
}

// The survey's bounds, points and color depth as a pass of Read's points gives them.
void ExpectSurveyLikeReadPoints(const std::filesystem::path& path, size_t batch_points) {
  auto reader = OpenScan(path);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  const auto survey = SurveyScan(**reader, batch_points);
  ASSERT_TRUE(survey.ok()) << survey.status().ToString();
  constexpr double inf = std::numeric_limits<double>::infinity();
  Bounds expected{{inf, inf, inf}, {-inf, -inf, -inf}};
  uint64_t points = 0;
  uint16_t max_color = 0;
  PointBatch batch;
  for (;;) {
    const auto n = (*reader)->Read(batch, batch_points);
    ASSERT_TRUE(n.ok());
    if (*n == 0) break;
    points += *n;
    for (size_t i = 0; i < *n; ++i) {
      for (int a = 0; a < 3; ++a) {
        expected.min[a] = std::min(expected.min[a], batch.xyz[i][a]);
        expected.max[a] = std::max(expected.max[a], batch.xyz[i][a]);
      }
      if (!batch.rgb.empty()) max_color = std::max({max_color, batch.rgb[i][0], batch.rgb[i][1], batch.rgb[i][2]});
    }
  }
  EXPECT_EQ(survey->points, points) << path;
  EXPECT_EQ(survey->bounds.min, expected.min) << path;
  EXPECT_EQ(survey->bounds.max, expected.max) << path;
  EXPECT_EQ(survey->color_bits, max_color <= 255 ? 8 : (*reader)->info().stored_color_bits) << path;
}

// LAS and plain PLY readers take the survey's extremes from the stored values (LAS: the integers,
// through a scale of either sign); the generic survey takes them from Read's points.
TEST(SurveyScan, BoundsFromStoredValuesEqualThoseOfReadPoints) {
  testing::ScratchDir dir;
  auto points = testing::RandomLasPoints(1000, 11);
  for (auto& p : points) p.rgb = {static_cast<uint16_t>(p.rgb[0] & 255), p.rgb[1], p.rgb[2]};
  for (int format : {0, 3, 7}) {
    for (double scale : {0.01, -0.003, 3.0}) {
      testing::LasSpec spec;
      spec.format = format;
      spec.minor = format < 6 ? 2 : 4;
      spec.scale = scale;
      spec.offset = scale < 0 ? -2.5e5 : 123.25;
      const auto path = dir / ("s" + std::to_string(format) + std::to_string(scale) + ".las");
      testing::WriteBytes(path, testing::MakeLas(spec, points));
      for (size_t batch : {size_t{7}, size_t{1} << 16}) ExpectSurveyLikeReadPoints(path, batch);
    }
  }
  std::mt19937 rng(13);
  for (const char* type : {"float", "double"}) {
    std::string ply = std::string("ply\nformat binary_little_endian 1.0\nelement vertex 500\nproperty ") + type +
                      " x\nproperty " + type + " y\nproperty " + type + " z\nproperty uchar red\n" +
                      "property uchar green\nproperty uchar blue\nend_header\n";
    for (int i = 0; i < 500; ++i) {
      for (int a = 0; a < 3; ++a) {
        const double v = (static_cast<double>(rng() % 200001) - 100000.0) / 7.0;
        if (type[0] == 'f') {
          const float f = i == 3 && a == 0 ? -0.0f : static_cast<float>(v);
          ply.append(reinterpret_cast<const char*>(&f), 4);
        } else {
          ply.append(reinterpret_cast<const char*>(&v), 8);
        }
      }
      for (int c = 0; c < 3; ++c) ply.push_back(static_cast<char>(rng() % 200));
    }
    const auto path = dir / (std::string(type) + ".ply");
    testing::WriteBytes(path, std::vector<uint8_t>(ply.begin(), ply.end()));
    for (size_t batch : {size_t{7}, size_t{1} << 16}) ExpectSurveyLikeReadPoints(path, batch);
  }
}

TEST(Voxelizer, NonFinitePointIsAnError) {
  VoxelizeOptions options;
  options.depth = 4;
  auto grid = VoxelizeInMemory({{0, 0, 0}, {INFINITY, 0, 0}}, {}, options);
  EXPECT_EQ(grid.status().code(), StatusCode::kMalformed);
}

TEST(Voxelizer, EveryPointLandsInTheVoxelHoldingIt) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::vector<std::array<double, 3>> xyz(5000);
  for (auto& p : xyz) p = {u(rng), u(rng), u(rng) * 0.1};
  VoxelizeOptions options;
  options.voxel_size = 0.7;
  auto grid = VoxelizeInMemory(xyz, {}, options);
  ASSERT_TRUE(grid.ok());
  EXPECT_TRUE(std::is_sorted(grid->morton.begin(), grid->morton.end()));
  EXPECT_EQ(std::adjacent_find(grid->morton.begin(), grid->morton.end()), grid->morton.end());
  for (const auto& p : xyz) {
    uint32_t cell[3];
    for (int a = 0; a < 3; ++a) cell[a] = static_cast<uint32_t>(std::floor((p[a] - grid->origin[a]) / grid->voxel_size));
    const uint64_t code = MortonEncode(cell[0], cell[1], cell[2]);
    ASSERT_TRUE(std::binary_search(grid->morton.begin(), grid->morton.end(), code));
    const auto centre = grid->VoxelCentre(code);
    for (int a = 0; a < 3; ++a) EXPECT_LE(std::abs(centre[a] - p[a]), grid->voxel_size / 2 + 1e-9);
  }
}

TEST(Voxelizer, RealScansMatchTheArchitectureTable) {
  SKIP_WITHOUT_DATA();
  const std::pair<const char*, double> cases[] = {{"autzen_trim_pdrf3_rgb.las", 4.0},
                                                  {"pcx_guanyin_cc-by-4.0_rgb.ply", 0.002}};
  const size_t expected[] = {36931, 215979};  // ../shared/ARCHITECTURE.md, "Facts measured on real scans"
  for (int i = 0; i < 2; ++i) {
    auto reader = OpenScan(testing::DataDir() / cases[i].first);
    ASSERT_TRUE(reader.ok());
    VoxelizeOptions options;
    options.voxel_size = cases[i].second;
    auto grid = Voxelize(**reader, options);
    ASSERT_TRUE(grid.ok()) << grid.status().ToString();
    EXPECT_EQ(grid->morton.size(), expected[i]) << cases[i].first;
  }
}

}  // namespace
}  // namespace pointdag

namespace pointdag {
namespace {

size_t Entries(const std::filesystem::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

TEST(ChunkedVoxelizer, SpillingChunksGivesTheSameGridAndCleansUp) {
  SKIP_WITHOUT_DATA();
  testing::ScratchDir spill;
  for (const char* file : {"lion_takanawa_pdrf7_rgb.las", "pcx_guanyin_cc-by-4.0_rgb.ply"}) {
    auto reader = OpenScan(testing::DataDir() / file);
    ASSERT_TRUE(reader.ok());
    VoxelizeOptions options;
    options.voxel_size = 0.005;
    auto in_memory = Voxelize(**reader, options);
    ASSERT_TRUE(in_memory.ok());
    EXPECT_EQ(in_memory->chunk_levels, 0);
    for (uint64_t budget : {200000u, 20000u, 1000u}) {
      options.max_points_in_memory = budget;
      options.spill_dir = spill.path();
      size_t chunks = 0, voxels_seen = 0;
      options.on_chunk = [&](const VoxelGrid& grid, size_t first) {
        ++chunks;
        EXPECT_EQ(first, voxels_seen);  // chunks arrive in order, each exactly once
        voxels_seen = grid.morton.size();
        return Status::Ok();
      };
      auto chunked = Voxelize(**reader, options);
      ASSERT_TRUE(chunked.ok()) << chunked.status().ToString();
      EXPECT_GT(chunked->chunk_levels, 0);
      EXPECT_GT(chunks, 1u);
      EXPECT_EQ(voxels_seen, chunked->morton.size());
      EXPECT_EQ(chunked->morton, in_memory->morton) << file << " budget " << budget;
      EXPECT_EQ(chunked->colors, in_memory->colors);
      EXPECT_EQ(Entries(spill.path()), 0u) << "spill files left behind";
    }
  }
}

// Fails on its second pass, after some points have already been spilled.
class FailingSecondPass final : public ScanReader {
 public:
  explicit FailingSecondPass(size_t n) : n_(n) {
    info_.point_count = n;
    info_.has_color = false;
  }
  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override {
    batch.clear();
    if (pass_ == 2 && next_ > n_ / 2) return IoError("disk went away");
    const size_t n = std::min(max_points, n_ - next_);
    for (size_t i = 0; i < n; ++i) batch.xyz.push_back({double(next_ + i), double((next_ + i) % 7), 0.0});
    next_ += n;
    return n;
  }
  Status Rewind() override {
    ++pass_;
    next_ = 0;
    return Status::Ok();
  }

 private:
  size_t n_, next_ = 0;
  int pass_ = 0;
};

TEST(ChunkedVoxelizer, FailureMidPassLeavesNoSpillFiles) {
  testing::ScratchDir spill;
  FailingSecondPass reader(100000);
  VoxelizeOptions options;
  options.depth = 12;
  options.batch_points = 1000;
  options.max_points_in_memory = 1000;
  options.spill_dir = spill.path();
  const auto result = Voxelize(reader, options);
  EXPECT_EQ(result.status().code(), StatusCode::kIoError);
  EXPECT_EQ(Entries(spill.path()), 0u);
}

}  // namespace
}  // namespace pointdag
