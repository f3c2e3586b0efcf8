// Light space of a shadow DAG (shadow_dag.h): the frame that turns a point of the dataset's grid into
// a cell of the light-space grid.
//
// Axes: z' = the light's travel; x' = the world axis least aligned with z' (the first of x, y, z on
// a tie), made perpendicular to z' and normalized; y' = z' × x'. The light-space cube is centred on
// the dataset's cube [0, 2^depth]^3 and its half side is the largest half extent of that cube along
// x', y', z', so it covers the whole dataset cube; it has 2^light_depth cells per side.
// With light_depth >= depth + 2 a cell's diagonal is at most sqrt(3)·sqrt(3)/4 = 0.75 voxel, so two
// voxel centres (at least 1 apart) never share a cell.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "pointdag/status.h"

namespace pointdag {

constexpr int kMaxLightDepth = 21;  // light-space Morton codes in 63 bits, as the codec's

class LightFrame {
 public:
  // kInvalidArgument: travel not finite or shorter than 1e-9; depth outside 2..21; light_depth
  // outside depth+2 .. min(depth+8, 21).
  static StatusOr<LightFrame> Create(const std::array<double, 3>& travel, int depth, int light_depth);

  // The cell (x', y', z') holding a point of the dataset's grid, or nothing outside the light cube
  // (or for NaN). A point on the cube's far faces belongs to the last cell.
  std::optional<std::array<uint32_t, 3>> Cell(const std::array<double, 3>& grid_point) const;

  // The grid point at light-space coordinates q (0 .. 2·half_side along x', y', z').
  std::array<double, 3> GridPoint(const std::array<double, 3>& q) const;

  const std::array<double, 3>& travel() const { return travel_; }  // as given (z' is it normalized)
  const std::array<std::array<double, 3>, 3>& axes() const { return axes_; }  // rows x', y', z'
  double half_side() const { return half_side_; }
  int depth() const { return depth_; }
  int light_depth() const { return light_depth_; }
  double cell_size() const { return cell_; }  // in voxels

 private:
  std::array<double, 3> travel_{};
  std::array<std::array<double, 3>, 3> axes_{};  // rows: x', y', z'
  int depth_ = 0;
  int light_depth_ = 0;
  double half_side_ = 0;
  double cell_ = 0;
};

}  // namespace pointdag
