// Stage 10a (issue #16): one shadow ray at a time through an Svdag's structure.
//
// How: a front-to-back depth-first descent of the DAG along the half-line from a voxel's centre
// towards the light (hierarchical empty-space skipping: an empty octant is never entered). The
// children of a node are visited in octant order XOR the ray's sign bits, which is front to back
// for any ray; their slab intervals come from four planes per axis computed once per node. Boxes
// are tested with a margin of kMargin grid units, far above the rounding of the slab test in
// a 2^21 grid, so every cell that RayMeetsCell() could accept is reached; each reached voxel is
// then decided by RayMeetsCell() itself, which keeps the tie rules (grazed edges and corners) of
// voxel_shadows.h. The descent stops at the first blocking voxel: any one decides "shadowed".
// Most shadowed voxels are blocked by a voxel of their own 4x4x4 brick, so that brick (found by
// the voxel's coordinates, remembered while consecutive voxels share it) is tried before the
// descent, which then skips it.
//
// One caster per thread (it keeps its traversal stack); the DAG is only read.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "pointdag/dag/svdag.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {

class ShadowRayCaster {
 public:
  // `travel`: finite and not zero (the light's direction of travel, as in light.h); `bias`: the
  // light's self-shadow bias (occluders count beyond that distance only).
  ShadowRayCaster(const Svdag& dag, const std::array<double, 3>& travel, double bias = 0);

  // Does the ray from the centre of `voxel` towards the light meet another occupied voxel?
  bool Blocked(const std::array<uint32_t, 3>& voxel);

 private:
  struct Entry {
    uint32_t ref;
    int level;
    std::array<uint32_t, 3> lo;
  };

  // Entry and exit parameters of the ray, per axis and child bit, for the margin-grown halves of
  // a node at `lo` whose children have side `half`; a child is reached when its three intervals
  // and t >= 0 overlap. Not t > bias: pruning by the bias too measured ~10 % slower at bias 0 (a
  // member instead of a constant in the hottest test); RayMeetsCell() applies it to every voxel
  // reached. A biased origin instead (the ray starting at c - bias * travel) was tried and dropped:
  // its rounding decides grazed edges, so a larger bias could shadow more.
  struct ChildSlabs {
    double enter[3][2];
    double exit[3][2];
    bool Reach(uint32_t octant) const {
      const uint32_t bx = (octant >> 2) & 1u, by = (octant >> 1) & 1u, bz = octant & 1u;
      const double t0 = std::max(std::max(enter[0][bx], enter[1][by]), std::max(enter[2][bz], 0.0));
      const double t1 = std::min(std::min(exit[0][bx], exit[1][by]), exit[2][bz]);
      return t0 <= t1;
    }
  };
  void Slabs(const std::array<uint32_t, 3>& lo, uint32_t half, ChildSlabs& slabs) const;
  bool BrickBlocks(uint64_t brick, const std::array<uint32_t, 3>& lo) const;
  // The brick holding `voxel` (an occupied voxel): its corner and index into dag.leaves.
  void FindOwnBrick(const std::array<uint32_t, 3>& voxel);

  const Svdag& dag_;
  std::array<double, 3> travel_;
  double bias_;
  std::array<double, 3> inv_{};   // 1 / component of -travel, towards the light (unused when zero)
  std::array<bool, 3> flat_{};    // the ray keeps this coordinate
  uint32_t flip_ = 0;             // octant bits of the axes the ray runs down: front-to-back order
  std::array<double, 3> origin_{};
  std::array<uint32_t, 3> self_{};
  std::array<uint32_t, 3> own_lo_{~0u, ~0u, ~0u};
  uint32_t own_ref_ = 0;
  // Depth first, at most 8 children pushed per level on the way down.
  std::array<Entry, 8 * kMaxDepth + 1> stack_;
};

}  // namespace pointdag
