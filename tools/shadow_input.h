// `pointdag shadow`'s input: a scan voxelized as `encode --georeference` does (ENU metres about the
// scan's centre when it has a CRS, its own frame otherwise), or a .pdag decoded as stored.
#pragma once

#include <filesystem>
#include <optional>

#include "pointdag/dag/svdag.h"
#include "pointdag/status.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

struct ShadowInput {
  VoxelGrid grid;
  Svdag dag;
  bool georeferenced = false;  // the grid's axes are ENU about (latitude, longitude)
  double latitude_deg = 0, longitude_deg = 0;
  double load_seconds = 0;
};

// Exactly one of voxel_size and depth for a scan; neither for a .pdag (it has its own grid).
StatusOr<ShadowInput> LoadShadowInput(const std::filesystem::path& path, std::optional<double> voxel_size,
                                      std::optional<int> depth);

}  // namespace pointdag
