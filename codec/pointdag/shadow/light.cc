#include "pointdag/shadow/light.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace pointdag {

Status CheckShadowBias(double bias) {
  if (!std::isfinite(bias) || bias < 0 || bias > kMaxShadowBias) {
    return InvalidArgument("shadow bias must be a number of voxels from 0 to 16");
  }
  return Status::Ok();
}

StatusOr<Light> LightFromDirection(double x, double y, double z) {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
    return InvalidArgument("light direction has a NaN or infinite component");
  }
  // Scale by the largest component first so that tiny (subnormal) and huge vectors normalize
  // without underflow or overflow.
  const double scale = std::max({std::fabs(x), std::fabs(y), std::fabs(z)});
  if (scale == 0) return InvalidArgument("light direction (0, 0, 0) has no direction");
  x /= scale, y /= scale, z /= scale;
  const double length = std::sqrt(x * x + y * y + z * z);
  Light light;
  light.travel = {x / length, y / length, z / length};
  return light;
}

}  // namespace pointdag
