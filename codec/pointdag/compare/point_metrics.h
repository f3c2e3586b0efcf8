// Whole-pipeline quality against the ORIGINAL points, as MPEG's pc_error defines it:
// - D1 (point-to-point): each point of one cloud to its nearest neighbour in the other, squared
//   distance averaged; both directions, the worse one counts. PSNR = 10 log10(3 p^2 / MSE) with p
//   the grid's side in source units.
// - color: each point's color against its nearest neighbour's (Y, BT.709), both directions, the
//   worse one counts.
// Nearest neighbours come from FLANN's exact single kd-tree. The correspondences are found once;
// any decoded color array of the same voxels is then scored in linear time.
#pragma once

#include <array>
#include <filesystem>
#include <span>
#include <vector>

#include "pointdag/color/color_metrics.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

class OriginalCorrespondence {
 public:
  static StatusOr<OriginalCorrespondence> Build(const std::filesystem::path& scan, const VoxelGrid& grid);

  double d1_mse() const { return std::max(mse_original_to_voxels_, mse_voxels_to_original_); }
  double d1_psnr() const;
  // Symmetric PSNR-Y of voxel colors (parallel to grid.morton) against the original points' colors.
  double ColorPsnrY(std::span<const Rgb8> voxel_colors) const;
  bool has_color() const { return !original_colors_.empty(); }

 private:
  std::vector<Rgb8> original_colors_;      // 8-bit, as the voxelizer normalises them
  std::vector<uint32_t> nearest_voxel_;    // per original point
  std::vector<uint32_t> nearest_original_; // per voxel
  double mse_original_to_voxels_ = 0, mse_voxels_to_original_ = 0, peak_ = 1;
};


}  // namespace pointdag
