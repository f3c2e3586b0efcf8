#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "pointdag/dag/dag_builder.h"
#include "pointdag/voxelize/morton.h"
#include "test_util.h"

namespace pointdag {
namespace {

using testing::SurfaceVoxels;

Svdag Build(const std::vector<uint64_t>& codes, int depth, DagBuildOptions options = {}) {
  auto dag = BuildDag(codes, depth, options);
  EXPECT_TRUE(dag.ok()) << dag.status().ToString();
  return dag.ok() ? std::move(dag).value() : Svdag{};
}

// Reference mipmap order: every SVO node (level, key) in depth-first pre-order.
std::vector<std::pair<int, uint64_t>> PreorderNodes(const std::vector<uint64_t>& codes, int depth) {
  std::vector<std::pair<int, uint64_t>> nodes;
  for (int level = 0; level <= depth; ++level) {
    std::set<uint64_t> keys;
    for (uint64_t c : codes) keys.insert(c >> (3 * (depth - level)));
    for (uint64_t k : keys) nodes.emplace_back(level, k);
  }
  std::sort(nodes.begin(), nodes.end(), [depth](const auto& a, const auto& b) {
    const uint64_t pa = a.second << (3 * (depth - a.first)), pb = b.second << (3 * (depth - b.first));
    return pa != pb ? pa < pb : a.first < b.first;  // an ancestor precedes its descendants
  });
  return nodes;
}

class DagDepthTest : public ::testing::TestWithParam<int> {};

TEST_P(DagDepthTest, EnumeratesExactlyTheInputVoxelsInMortonOrder) {
  const int depth = GetParam();
  const auto codes = SurfaceVoxels(depth, 6000, static_cast<uint32_t>(depth));
  const Svdag dag = Build(codes, depth);
  EXPECT_TRUE(dag.Validate().ok());
  EXPECT_EQ(dag.MortonCodes(), codes);
  EXPECT_EQ(dag.RootCount(), codes.size());
  EXPECT_EQ(dag.VoxelCount(), codes.size());
}

TEST_P(DagDepthTest, ColorIndexIsTheMortonRank) {
  const int depth = GetParam();
  const auto codes = SurfaceVoxels(depth, 4000, 100u + static_cast<uint32_t>(depth));
  const Svdag dag = Build(codes, depth);
  for (size_t i = 0; i < codes.size(); ++i) {
    const auto c = MortonDecode(codes[i]);
    ASSERT_EQ(dag.ColorIndex(c[0], c[1], c[2]), std::optional<uint64_t>(i)) << "voxel " << i;
  }
}

TEST_P(DagDepthTest, MipmapIndicesArePreorderRanksOfEveryNode) {
  const int depth = GetParam();
  const auto codes = SurfaceVoxels(depth, 1500, 200u + static_cast<uint32_t>(depth));
  DagBuildOptions options;
  options.mode = CountMode::kMipmap;
  const Svdag dag = Build(codes, depth, options);
  EXPECT_TRUE(dag.Validate().ok());
  const auto nodes = PreorderNodes(codes, depth);
  EXPECT_EQ(dag.RootCount(), nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    const auto [level, key] = nodes[i];
    const auto c = MortonDecode(key);
    ASSERT_EQ(dag.MipColorIndex(c[0], c[1], c[2], level), std::optional<uint64_t>(i)) << "level " << level;
  }
  EXPECT_EQ(dag.VoxelCount(), codes.size());
  EXPECT_EQ(dag.MortonCodes(), codes);  // mipmap counts do not change the geometry
}

INSTANTIATE_TEST_SUITE_P(Depths, DagDepthTest, ::testing::Values(2, 3, 4, 6, 8, 9, 12, 21));

TEST(Dag, AnswersEveryOccupancyQueryLikeTheSvo) {
  const int depth = 5;
  const auto codes = SurfaceVoxels(depth, 3000, 42);
  const std::set<uint64_t> svo(codes.begin(), codes.end());
  const Svdag dag = Build(codes, depth);
  for (uint32_t x = 0; x < 32; ++x) {
    for (uint32_t y = 0; y < 32; ++y) {
      for (uint32_t z = 0; z < 32; ++z) {
        ASSERT_EQ(dag.Contains(x, y, z), svo.count(MortonEncode(x, y, z)) == 1) << x << "," << y << "," << z;
      }
    }
  }
  EXPECT_FALSE(dag.Contains(32, 0, 0));  // outside the grid
  EXPECT_FALSE(dag.MipColorIndex(0, 0, 0, 0).has_value());  // leaf mode has no mip indices
}

TEST(Dag, RandomQueriesOnADeepGrid) {
  const int depth = 14;
  const auto codes = SurfaceVoxels(depth, 20000, 9);
  const std::set<uint64_t> svo(codes.begin(), codes.end());
  const Svdag dag = Build(codes, depth);
  std::mt19937 rng(3);
  for (int i = 0; i < 200000; ++i) {
    // Half the queries near occupied voxels, half anywhere.
    uint32_t x, y, z;
    if (i % 2) {
      auto c = MortonDecode(codes[rng() % codes.size()]);
      x = c[0] ^ (rng() & 1), y = c[1] ^ (rng() & 1), z = c[2];
    } else {
      x = rng() & 0x3FFF, y = rng() & 0x3FFF, z = rng() & 0x3FFF;
    }
    ASSERT_EQ(dag.Contains(x, y, z), svo.count(MortonEncode(x, y, z)) == 1);
  }
}

TEST(Dag, IdenticalSubtreesAreStoredOnce) {
  // A full 16^3 cube: every node of a level is the same subtree.
  std::vector<uint64_t> cube(4096);
  for (uint64_t i = 0; i < cube.size(); ++i) cube[i] = i;
  const Svdag dag = Build(cube, 4);
  EXPECT_EQ(dag.UniqueNodeCount(), 3u);  // root, one level-1 node, one brick
  EXPECT_EQ(dag.leaves, std::vector<uint64_t>{~uint64_t{0}});
  EXPECT_EQ(dag.RootCount(), 4096u);
  // The floor of SurfaceVoxels repeats bricks too: far fewer unique bricks than bricks.
  const auto codes = SurfaceVoxels(10, 30000, 1);
  std::set<uint64_t> bricks;
  for (uint64_t c : codes) bricks.insert(c >> 6);
  EXPECT_LT(Build(codes, 10).leaves.size(), bricks.size() / 2);
}

TEST(Dag, UpperLevelsKeepTheirCountsInTheSeparateArray) {
  const auto codes = SurfaceVoxels(12, 5000, 4);
  const Svdag dag = Build(codes, 12);
  EXPECT_TRUE(dag.IsUpperLevel(4));
  EXPECT_FALSE(dag.IsUpperLevel(5));
  EXPECT_FALSE(dag.upper_counts.empty());
  EXPECT_EQ(dag.upper_counts[0], codes.size());  // the root's count
}

// A hash that collides constantly must never merge different subtrees: the result is identical.
TEST(Dag, WeakHashMergesNothingWrongly) {
  for (int depth : {4, 7, 10}) {
    const auto codes = SurfaceVoxels(depth, 5000, 77);
    const Svdag reference = Build(codes, depth);
    for (uint64_t mask : {uint64_t{0}, uint64_t{1}, uint64_t{0xF}}) {
      DagBuildOptions weak;
      weak.hash_mask = mask;
      const Svdag dag = Build(codes, depth, weak);
      EXPECT_EQ(dag, reference) << "depth " << depth << " hash mask " << mask;
      EXPECT_EQ(dag.MortonCodes(), codes);
    }
  }
}

TEST(Dag, ChunkedBuildEqualsOneGoBuild) {
  for (int depth : {5, 9, 12}) {
    const auto codes = SurfaceVoxels(depth, 20000, 5);
    for (DagBuildOptions options : {DagBuildOptions{}, DagBuildOptions{CountMode::kMipmap}}) {
      const Svdag reference = Build(codes, depth, options);
      for (int chunk_levels = 0; chunk_levels <= depth - 2; chunk_levels += 1 + depth / 4) {
        auto chunked = BuildDagChunked(codes, depth, chunk_levels, options);
        ASSERT_TRUE(chunked.ok()) << chunked.status().ToString();
        EXPECT_EQ(*chunked, reference) << "depth " << depth << " chunk levels " << chunk_levels;
      }
    }
  }
}

TEST(Dag, MergingTwoSubDagsEqualsBuildingTheUnion) {
  const int depth = 9;
  auto all = SurfaceVoxels(depth, 20000, 8);
  // Keep the voxels of two root octants only, and build each octant as its own sub-DAG.
  std::vector<uint64_t> left, right, both;
  for (uint64_t c : all) {
    const uint64_t octant = c >> (3 * (depth - 1));
    if (octant == 1) left.push_back(c & ((uint64_t{1} << (3 * (depth - 1))) - 1));
    if (octant == 6) right.push_back(c & ((uint64_t{1} << (3 * (depth - 1))) - 1));
    if (octant == 1 || octant == 6) both.push_back(c);
  }
  const Svdag a = Build(left, depth - 1), b = Build(right, depth - 1);
  const PlacedSubdag parts[] = {{&a, 1}, {&b, 6}};
  auto merged = MergeSubdags(parts, depth);
  ASSERT_TRUE(merged.ok()) << merged.status().ToString();
  EXPECT_EQ(*merged, Build(both, depth));
  // Out of order, or of different modes: refused.
  const PlacedSubdag reversed[] = {{&b, 6}, {&a, 1}};
  EXPECT_EQ(MergeSubdags(reversed, depth).status().code(), StatusCode::kInvalidArgument);
  DagBuildOptions mip;
  mip.mode = CountMode::kMipmap;
  EXPECT_EQ(MergeSubdags(parts, depth, mip).status().code(), StatusCode::kInvalidArgument);
}

TEST(Dag, RejectsBadInput) {
  EXPECT_EQ(BuildDag(std::vector<uint64_t>{}, 5).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildDag(std::vector<uint64_t>{5, 3}, 5).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildDag(std::vector<uint64_t>{3, 3}, 5).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildDag(std::vector<uint64_t>{uint64_t{1} << 15}, 5).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildDag(std::vector<uint64_t>{1}, 1).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildDag(std::vector<uint64_t>{1}, 22).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(BuildDagChunked(std::vector<uint64_t>{1}, 5, 4).status().code(), StatusCode::kInvalidArgument);
}

TEST(Dag, ValidateCatchesBrokenStructure) {
  const Svdag good = Build(SurfaceVoxels(7, 3000, 2), 7);
  ASSERT_TRUE(good.Validate().ok());
  Svdag bad = good;
  bad.nodes[1] = static_cast<uint32_t>(bad.nodes.size() + 5);  // root's first child points nowhere
  EXPECT_EQ(bad.Validate().code(), StatusCode::kCorrupt);
  bad = good;
  bad.nodes[bad.level_offsets[1]] += 1;  // a count that no longer adds up
  EXPECT_EQ(bad.Validate().code(), StatusCode::kCorrupt);
  bad = good;
  bad.leaves[0] = 0;
  EXPECT_EQ(bad.Validate().code(), StatusCode::kCorrupt);
  bad = good;
  bad.level_offsets.pop_back();
  EXPECT_EQ(bad.Validate().code(), StatusCode::kCorrupt);
}

}  // namespace
}  // namespace pointdag
