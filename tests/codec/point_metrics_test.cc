#include <gtest/gtest.h>

#include "pointdag/compare/point_metrics.h"
#include "pointdag/read/memory_reader.h"
#include "pointdag/voxelize/voxelizer.h"
#include "test_util.h"

namespace pointdag {
namespace {

// Points on integer coordinates with a 1-unit grid at their minimum: every voxel centre sits half
// a unit off its point on each axis, so D1's squared distance is exactly 0.75 both ways. Points sit
// on voxel corners, so nearest neighbours tie; one color for all keeps color errors exact anyway.
TEST(PointMetrics, KnownDistancesAndExactColors) {
  testing::ScratchDir dir;
  std::string ply = "ply\nformat ascii 1.0\nelement vertex 64\nproperty double x\nproperty double y\nproperty double z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  std::vector<std::array<double, 3>> xyz;
  std::vector<std::array<uint16_t, 3>> rgb;
  for (int x = 0; x < 4; ++x) {
    for (int y = 0; y < 4; ++y) {
      for (int z = 0; z < 4; ++z) {
        ply += std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + " 100 150 200\n";
        xyz.push_back({double(x), double(y), double(z)});
        rgb.push_back({100, 150, 200});
      }
    }
  }
  std::ofstream(dir / "grid.ply") << ply;
  MemoryScanReader reader(xyz, rgb);
  VoxelizeOptions options;
  options.voxel_size = 1.0;
  auto grid = Voxelize(reader, options);
  ASSERT_TRUE(grid.ok());
  ASSERT_EQ(grid->morton.size(), 64u);
  auto original = OriginalCorrespondence::Build(dir / "grid.ply", *grid);
  ASSERT_TRUE(original.ok()) << original.status().ToString();
  EXPECT_DOUBLE_EQ(original->d1_mse(), 0.75);
  EXPECT_NEAR(original->d1_psnr(), 10 * std::log10(3.0 * 4 * 4 / 0.75), 1e-9);  // peak: the 4-unit grid side
  EXPECT_TRUE(std::isinf(original->ColorPsnrY(grid->colors)));
  auto darker = grid->colors;
  for (Rgb8& c : darker) c = {uint8_t(c.r / 2), uint8_t(c.g / 2), uint8_t(c.b / 2)};
  const double dy = LumaBt709({100, 150, 200}) - LumaBt709({50, 75, 100});
  EXPECT_NEAR(original->ColorPsnrY(darker), 20 * std::log10(255.0 / dy), 1e-9);
}

}  // namespace
}  // namespace pointdag
