// Writes voxels (centres in source units, 8-bit colors) as binary little-endian PLY.
// Coordinates are doubles: georeferenced scans (Lambert-93, UTM) lose centimetres in float.
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

// A per-voxel float property written after the colors (a shadow bit, sun hours): one value a voxel.
struct PlyScalar {
  std::string name;
  std::span<const float> values;
};

// kInvalidArgument when `scalar` has not one value per voxel.
Status WriteVoxelsPly(const std::filesystem::path& path, const VoxelGrid& grid,
                      const std::optional<PlyScalar>& scalar = std::nullopt);

}  // namespace pointdag
