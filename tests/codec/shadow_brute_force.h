// Shared by the exact-shadow tests (shadow_voxels_test.cc, shadow_bias_test.cc): the definition of
// voxel_shadows.h taken literally, and ShadowedVoxels unwrapped.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "pointdag/shadow/voxel_shadows.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag::testing {

// Every other voxel tested against the ray from each centre, beyond the light's bias. O(n^2).
inline std::vector<uint8_t> BruteForceShadows(const std::vector<uint64_t>& codes, const Light& light) {
  std::vector<std::array<uint32_t, 3>> cells;
  for (uint64_t code : codes) cells.push_back(MortonDecode(code));
  std::vector<uint8_t> shadowed(cells.size(), 0);
  for (size_t i = 0; i < cells.size(); ++i) {
    const std::array<double, 3> centre{cells[i][0] + 0.5, cells[i][1] + 0.5, cells[i][2] + 0.5};
    for (size_t j = 0; j < cells.size() && !shadowed[i]; ++j) {
      if (j != i && RayMeetsCell(centre, light.travel, cells[j], light.bias_voxels)) shadowed[i] = 1;
    }
  }
  return shadowed;
}

// ShadowedVoxels' answer, or nothing with a test failure.
inline std::vector<uint8_t> Shadows(const Svdag& dag, const Light& light, int threads = 0) {
  auto shadowed = ShadowedVoxels(dag, light, threads);
  EXPECT_TRUE(shadowed.ok()) << shadowed.status().ToString();
  return shadowed.ok() ? shadowed.value() : std::vector<uint8_t>{};
}

}  // namespace pointdag::testing
