// The tests' own reading of a .glb as a 3D Tiles runtime reads it: GLB chunks, the glTF JSON, the
// EXT_meshopt_compression streams decoded by libmeshoptimizer, positions placed by the node matrix
// and turned z-up ((x, y, z) -> (x, -z, y)) as 3D Tiles does with glTF content.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag::testing {

struct GlbPoints {
  nlohmann::json gltf;
  std::vector<std::array<uint16_t, 3>> cells;       // POSITION as stored
  std::vector<std::array<double, 3>> positions;     // in the tileset's (z-up) frame
  std::vector<Rgb8> colors;                         // empty without COLOR_0
  bool padding_zero = true;                         // every padding byte of both streams is 0
};

// Records a gtest failure for every rule of the format it finds broken (and returns what it could read).
GlbPoints ReadGlb(std::span<const uint8_t> glb);

}  // namespace pointdag::testing
