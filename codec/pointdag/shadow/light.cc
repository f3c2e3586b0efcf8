#include "pointdag/shadow/light.h"

#include <algorithm>
#include <cmath>

namespace pointdag {

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
