// Stage 10 (beside the codec, issue #16): the directional light that voxelized shadows are built for.
//
// Contract: a light is the unit direction light *travels* (from the light into the scene), in the
// dataset's own axes: x, y, z with z up — for a georeferenced dataset those are ENU (east, north,
// up), so the sun's direction from solar_position.h applies as is. The voxel grid is axis-aligned
// with those axes and uniformly scaled, so the same direction holds in grid units.
// A light below the horizon (the sun at night) puts every voxel in shadow; `below_horizon` says so
// and every consumer answers "shadowed" without casting a ray.
//
// Self-shadow bias: the definition (voxel_shadows.h) lets a voxel's ray graze the cube of
// its neighbour, so voxelized flat ground shadows itself whenever the light is lower than 45°
// ("shadow acne"). `bias_voxels` > 0 ignores occluders the ray meets within that distance of the
// voxel's centre (t > bias instead of t > 0, grid units): flat ground at elevation e is lit once
// bias >= 0.5 / sin e. The default 0 is exactly the definition; a bias of 0.5 or less changes
// nothing (no ray leaves its own cube before t = 0.5).
#pragma once

#include <array>

#include "pointdag/status.h"

namespace pointdag {

struct Light {
  std::array<double, 3> travel{0, 0, -1};  // unit length
  bool below_horizon = false;
  double bias_voxels = 0;  // finite, 0..kMaxShadowBias
};

constexpr double kMaxShadowBias = 16;

// kInvalidArgument unless `bias` is finite and within 0..kMaxShadowBias.
Status CheckShadowBias(double bias);

// A light travelling along (x, y, z), normalized. kInvalidArgument for NaN/Inf components or a
// vector too short to have a direction.
StatusOr<Light> LightFromDirection(double x, double y, double z);

}  // namespace pointdag
