#include "pointdag/shadow/light_frame.h"

#include <cmath>

namespace pointdag {

StatusOr<LightFrame> LightFrame::Create(const std::array<double, 3>& travel, int depth, int light_depth) {
  if (depth < 2 || depth > 21) return InvalidArgument("grid depth must be in 2..21");
  if (light_depth < depth + 2 || light_depth > depth + 8 || light_depth > kMaxLightDepth) {
    return InvalidArgument("light depth must be in depth+2 .. min(depth+8, 21)");
  }
  const double length = std::sqrt(travel[0] * travel[0] + travel[1] * travel[1] + travel[2] * travel[2]);
  if (!std::isfinite(length) || length < 1e-9) return InvalidArgument("light travel must be a finite non-zero vector");
  LightFrame f;
  f.travel_ = travel;
  f.depth_ = depth;
  f.light_depth_ = light_depth;
  auto& z = f.axes_[2];
  for (int i = 0; i < 3; ++i) z[i] = travel[i] / length;
  int helper = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(z[i]) < std::abs(z[helper])) helper = i;
  }
  auto& x = f.axes_[0];
  x = {0, 0, 0};
  x[helper] = 1;
  for (int i = 0; i < 3; ++i) x[i] -= z[helper] * z[i];
  const double xl = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  for (double& c : x) c /= xl;
  f.axes_[1] = {z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]};
  const double half_grid = std::ldexp(0.5, depth);
  for (const auto& axis : f.axes_) {
    f.half_side_ = std::max(f.half_side_, half_grid * (std::abs(axis[0]) + std::abs(axis[1]) + std::abs(axis[2])));
  }
  f.cell_ = std::ldexp(2 * f.half_side_, -light_depth);
  return f;
}

std::optional<std::array<uint32_t, 3>> LightFrame::Cell(const std::array<double, 3>& p) const {
  const double half_grid = std::ldexp(0.5, depth_);
  const std::array<double, 3> d{p[0] - half_grid, p[1] - half_grid, p[2] - half_grid};
  const uint32_t side = uint32_t{1} << light_depth_;
  std::array<uint32_t, 3> cell{};
  for (int i = 0; i < 3; ++i) {
    const double q = (axes_[i][0] * d[0] + axes_[i][1] * d[1] + axes_[i][2] * d[2] + half_side_) / cell_;
    if (!(q >= 0 && q <= side)) return std::nullopt;  // also NaN
    cell[i] = std::min(static_cast<uint32_t>(q), side - 1);
  }
  return cell;
}

std::array<double, 3> LightFrame::GridPoint(const std::array<double, 3>& q) const {
  const double half_grid = std::ldexp(0.5, depth_);
  std::array<double, 3> p{half_grid, half_grid, half_grid};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) p[j] += axes_[i][j] * (q[i] - half_side_);
  }
  return p;
}

}  // namespace pointdag
