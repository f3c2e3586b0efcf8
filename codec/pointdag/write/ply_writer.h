// Writes voxels (centres in source units, 8-bit colors) as binary little-endian PLY.
// Coordinates are doubles: georeferenced scans (Lambert-93, UTM) lose centimetres in float.
#pragma once

#include <filesystem>
#include <vector>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

Status WriteVoxelsPly(const std::filesystem::path& path, const VoxelGrid& grid);

}  // namespace pointdag
