// Stage 10a (issue #16): one shadow ray at a time through an Svdag's structure.
//
// How: a front-to-back depth-first descent of the DAG along the half-line from a voxel's centre
// towards the light (hierarchical empty-space skipping: an empty octant is never entered). Boxes
// are tested with a margin of kMargin grid units, far above the rounding of the slab test in
// a 2^21 grid, so every cell that RayMeetsCell() could accept is reached; each reached voxel is
// then decided by RayMeetsCell() itself, which keeps the tie rules (grazed edges and corners) of
// voxel_shadows.h. The descent stops at the first blocking voxel: any one decides "shadowed".
//
// One caster per thread (it keeps its traversal stack); the DAG is only read.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "pointdag/dag/svdag.h"

namespace pointdag {

class ShadowRayCaster {
 public:
  // `travel`: finite and not zero (the light's direction of travel, as in light.h).
  ShadowRayCaster(const Svdag& dag, const std::array<double, 3>& travel);

  // Does the ray from the centre of `voxel` towards the light meet another occupied voxel?
  bool Blocked(const std::array<uint32_t, 3>& voxel);

 private:
  struct Entry {
    uint32_t ref;
    int level;
    std::array<uint32_t, 3> lo;
  };

  // Whether the margin-grown box [lo, lo + size]^3 meets the ray at some t >= 0; `t_enter` is where.
  bool Enters(const std::array<uint32_t, 3>& lo, uint32_t size, double& t_enter) const;
  bool BrickBlocks(uint64_t brick, const std::array<uint32_t, 3>& lo) const;

  const Svdag& dag_;
  std::array<double, 3> travel_;
  std::array<double, 3> inv_{};   // 1 / component of -travel, towards the light (unused when zero)
  std::array<bool, 3> flat_{};    // the ray keeps this coordinate
  std::array<double, 3> origin_{};
  std::array<uint32_t, 3> self_{};
  std::vector<Entry> stack_;
};

}  // namespace pointdag
