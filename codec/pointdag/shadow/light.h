// Stage 10 (beside the codec, issue #16): the directional light that voxelized shadows are built for.
//
// Contract: a light is the unit direction light *travels* (from the light into the scene), in the
// dataset's own axes: x, y, z with z up — for a georeferenced dataset those are ENU (east, north,
// up), so the sun's direction from solar_position.h applies as is. The voxel grid is axis-aligned
// with those axes and uniformly scaled, so the same direction holds in grid units.
// A light below the horizon (the sun at night) puts every voxel in shadow; `below_horizon` says so
// and every consumer answers "shadowed" without casting a ray.
#pragma once

#include <array>

#include "pointdag/status.h"

namespace pointdag {

struct Light {
  std::array<double, 3> travel{0, 0, -1};  // unit length
  bool below_horizon = false;
};

// A light travelling along (x, y, z), normalized. kInvalidArgument for NaN/Inf components or a
// vector too short to have a direction.
StatusOr<Light> LightFromDirection(double x, double y, double z);

}  // namespace pointdag
