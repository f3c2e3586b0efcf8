#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "pointdag/color/color_metrics.h"
#include "pointdag/ingest.h"
#include "pointdag/tile/tiler.h"
#include "pointdag/voxelize/morton.h"
#include "test_util.h"

namespace pointdag {
namespace {

// A wavy surface on a depth-10 grid with smooth colors: three levels of 256^3 tiles.
VoxelGrid SurfaceGrid() {
  VoxelGrid grid;
  grid.depth = 10;
  grid.voxel_size = 0.25;
  grid.origin = {100.0, -50.0, 3.0};
  grid.points_in = 1;
  std::map<uint64_t, Rgb8> voxels;
  for (uint32_t x = 0; x < 1024; x += 3) {
    for (uint32_t y = 0; y < 1024; y += 3) {
      const auto z = static_cast<uint32_t>(512 + 300 * std::sin(x / 150.0) * std::cos(y / 170.0));
      voxels[MortonEncode(x, y, z)] = {static_cast<uint8_t>(x / 4), static_cast<uint8_t>(y / 4), static_cast<uint8_t>(z / 4)};
    }
  }
  for (const auto& [code, color] : voxels) {
    grid.morton.push_back(code);
    grid.colors.push_back(color);
  }
  grid.points_in = grid.morton.size();
  return grid;
}

TEST(Tiler, LevelsHoldTheExactMeanOfTheVoxelsTheyCover) {
  const VoxelGrid finest = SurfaceGrid();
  const VoxelGrid same = LevelGrid(finest, 2, 8);
  EXPECT_EQ(same.morton, finest.morton);
  EXPECT_EQ(same.colors, finest.colors);
  const VoxelGrid coarse = LevelGrid(finest, 0, 8);
  EXPECT_EQ(coarse.depth, 8);
  EXPECT_DOUBLE_EQ(coarse.voxel_size, 1.0);
  std::map<uint64_t, std::array<uint64_t, 4>> sums;
  for (size_t i = 0; i < finest.morton.size(); ++i) {
    auto& s = sums[finest.morton[i] >> 6];
    s[0] += finest.colors[i].r, s[1] += finest.colors[i].g, s[2] += finest.colors[i].b, s[3] += 1;
  }
  ASSERT_EQ(coarse.morton.size(), sums.size());
  size_t i = 0;
  for (const auto& [code, sum] : sums) {
    ASSERT_EQ(coarse.morton[i], code);
    const auto& s = sum;  // clang 14 cannot capture a structured binding
    const auto mean = [&](int c) { return static_cast<uint8_t>((s[c] + s[3] / 2) / s[3]); };
    ASSERT_EQ(coarse.colors[i], (Rgb8{mean(0), mean(1), mean(2)})) << "voxel " << i;
    ++i;
  }
}

TEST(Tiler, TilesDecodeBackToEveryLevelAndFormAnOctree) {
  const VoxelGrid finest = SurfaceGrid();
  TilingOptions options;
  options.colors.target_psnr_y = 40.0;
  EXPECT_EQ(options.geometry_coder, GeometryCoder::kTable);
  EXPECT_EQ(options.geometry_version, kPrefixRefsStreamVersion);
  EXPECT_EQ(options.colors.block_version, kFixedWeightCodesVersion);
  // What the daemon and `pointdag export` tile with keeps those streams, at any quality.
  const TilingOptions ingest = IngestTilingOptions(8, 34.0);
  EXPECT_EQ(ingest.geometry_version, kPrefixRefsStreamVersion);
  EXPECT_EQ(ingest.colors.block_version, kFixedWeightCodesVersion);
  EXPECT_EQ(ingest.colors.target_psnr_y, 34.0);
  auto set = BuildTiles(finest, ScanInfo{}, "surface", options);
  ASSERT_TRUE(set.ok()) << set.status().ToString();
  EXPECT_EQ(set->levels, 3);
  EXPECT_EQ(set->tile_depth, 8);
  std::set<TileKey> keys;
  for (const Tile& t : set->tiles) keys.insert(t.key);
  ASSERT_EQ(keys.size(), set->tiles.size());
  EXPECT_EQ(std::count_if(keys.begin(), keys.end(), [](const TileKey& k) { return k.level == 0; }), 1);
  for (int level = 0; level < set->levels; ++level) {
    const VoxelGrid expected = LevelGrid(finest, level, 8);
    std::vector<uint64_t> codes;
    std::vector<Rgb8> colors;
    for (const Tile& t : set->tiles) {
      if (t.key.level != level) continue;
      if (level > 0) {
        EXPECT_TRUE(keys.count({level - 1, t.key.x / 2, t.key.y / 2, t.key.z / 2})) << "orphan tile";
      }
      const auto file = ParsePdag(t.bytes);
      ASSERT_TRUE(file.ok() && !file->geometry.empty());
      EXPECT_EQ(file->geometry[0], options.geometry_version) << "tiles take the faster-decoding geometry stream";
      ASSERT_GE(file->colors.size(), 2u);
      EXPECT_EQ(file->colors[1], kFixedWeightCodesVersion) << "and the faster-decoding block color stream";
      EXPECT_EQ(file->colors[0], kVoxelColorsOnly | static_cast<uint8_t>(ColorCodec::kVariableRate)) << "voxel colors only";
      for (const char* scan_wide : {"source", "crs", "grid_bounds"}) {
        EXPECT_FALSE(file->meta.contains(scan_wide)) << scan_wide << ": the dataset's description carries it once";
      }
      auto decoded = DecodePdag(*file);
      ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
      EXPECT_EQ(file->meta["tile"]["level"], level);
      EXPECT_EQ(file->meta["tile"]["x"], t.key.x);
      EXPECT_EQ(decoded->grid.morton.size(), t.voxels);
      EXPECT_DOUBLE_EQ(decoded->grid.voxel_size, expected.voxel_size);
      const double span = 256 * expected.voxel_size;
      EXPECT_DOUBLE_EQ(decoded->grid.origin[0], finest.origin[0] + t.key.x * span);
      const uint64_t tile_code = MortonEncode(t.key.x, t.key.y, t.key.z);
      for (uint64_t local : decoded->grid.morton) codes.push_back((tile_code << 24) | local);
      colors.insert(colors.end(), decoded->grid.colors.begin(), decoded->grid.colors.end());
    }
    // Tiles come sorted by key and Morton order within a level is tile order: no sort needed.
    ASSERT_EQ(codes, expected.morton) << "level " << level;
    EXPECT_GE(MeasureColorPsnr(expected.colors, colors).y, 40.0) << "level " << level;
  }
}

TEST(Tiler, ASmallGridIsOneTile) {
  VoxelGrid grid;
  grid.depth = 4;
  grid.morton = {0, 7, 100, 4095};
  grid.colors = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}, {10, 11, 12}};
  auto set = BuildTiles(grid, ScanInfo{}, "small", TilingOptions{});
  ASSERT_TRUE(set.ok());
  ASSERT_EQ(set->tiles.size(), 1u);
  EXPECT_EQ(set->levels, 1);
  auto decoded = DecodePdag(*ParsePdag(set->tiles[0].bytes));
  ASSERT_TRUE(decoded.ok());
  EXPECT_EQ(decoded->grid.morton, grid.morton);
  EXPECT_FALSE(BuildTiles(VoxelGrid{}, ScanInfo{}, "empty", TilingOptions{}).ok());
}

}  // namespace
}  // namespace pointdag
