// Stage 10a (issue #16): which voxels of a dataset are in shadow, exactly.
//
// Definition (the one every test and every other path must reproduce bit for bit): in grid units,
// voxel k is the closed cube [k, k + 1]^3 and its centre is k + 0.5. Voxel v is in shadow when the
// half-line from its centre towards the light, { c_v - t * travel : t > 0 }, meets the closed cube of
// another occupied voxel (its own cube excluded). With a self-shadow bias b = light.bias_voxels
// (light.h; 0 = the definition above), only the part t > b counts. RayMeetsCell() is that predicate; fast paths may
// find candidate cells any way they like (DAG traversal, DDA, with a safety margin) but decide
// with RayMeetsCell() so that ties (a ray grazing an edge) come out the same everywhere.
// A light below the horizon: every voxel is in shadow.
//
// Output order: the voxels' Morton order, which is the color index of a leaf-mode DAG (and of
// VoxelGrid::morton); for a mipmap-mode DAG it is the rank among its voxels, not the mip index.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/dag/svdag.h"
#include "pointdag/shadow/light.h"
#include "pointdag/status.h"

namespace pointdag {

// Does the half-line from `origin` (grid units) going against `travel` meet the closed cube of
// `cell` at some t > `bias` (`travel` unit length, so t is a distance)? The shared tie-breaking
// predicate of the definition above.
bool RayMeetsCell(const std::array<double, 3>& origin, const std::array<double, 3>& travel,
                  const std::array<uint32_t, 3>& cell, double bias = 0);

// One byte per voxel, 1 = shadowed, 0 = lit, in Morton order. `dag` is well formed (built here,
// or decoded and Validate()d). kInvalidArgument for a depth outside 2..21, a light whose travel
// is NaN, infinite or zero (unless below the horizon) or whose bias fails CheckShadowBias. `threads`: worker threads, 0 = one per
// core; the answer never depends on it. Cost: one ray per voxel, skipping empty octants.
StatusOr<std::vector<uint8_t>> ShadowedVoxels(const Svdag& dag, const Light& light, int threads = 0);

// Sun hours: per voxel, how many of `lights` light it (0..lights.size(), at most 65535 lights,
// else kInvalidArgument; a light below the horizon lights nothing).
StatusOr<std::vector<uint16_t>> LitSampleCounts(const Svdag& dag, std::span<const Light> lights, int threads = 0);

}  // namespace pointdag
