#include "pointdag/color/block_fit.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace pointdag {
namespace {

using Vec3 = std::array<double, 3>;

Vec3 ToVec(const Rgb8& c) { return {double(c.r), double(c.g), double(c.b)}; }

uint8_t ClampRound(double v) { return static_cast<uint8_t>(std::clamp(std::lround(v), 0l, 255l)); }

Rgb8 ToRgb(const Vec3& v) { return {ClampRound(v[0]), ClampRound(v[1]), ClampRound(v[2])}; }

double Sse(const Rgb8* colors, size_t n, const Endpoints& ends, int bits, double give_up_above) {
  double sse = 0;
  for (size_t i = 0; i < n; ++i) {
    sse += SquaredError(colors[i], Interpolate(ends, ChooseWeight(colors[i], ends, bits), bits));
    if (sse > give_up_above) break;
  }
  return sse;
}

// Least-squares endpoints for fixed weights: per channel, minimise sum((1-t)A + tB - c)^2.
bool RefineEndpoints(const Rgb8* colors, size_t n, int bits, Endpoints& ends) {
  const double m = double((1u << bits) - 1);
  double s00 = 0, s01 = 0, s11 = 0;
  Vec3 r0{}, r1{};
  for (size_t i = 0; i < n; ++i) {
    const double t = ChooseWeight(colors[i], ends, bits) / m, u = 1 - t;
    s00 += u * u, s01 += u * t, s11 += t * t;
    const Vec3 c = ToVec(colors[i]);
    for (int k = 0; k < 3; ++k) r0[k] += u * c[k], r1[k] += t * c[k];
  }
  const double det = s00 * s11 - s01 * s01;
  if (std::abs(det) < 1e-9) return false;
  Vec3 a, b;
  for (int k = 0; k < 3; ++k) {
    a[k] = (s11 * r0[k] - s01 * r1[k]) / det;
    b[k] = (s00 * r1[k] - s01 * r0[k]) / det;
  }
  ends = {ToRgb(a), ToRgb(b)};
  return true;
}

}  // namespace

uint32_t ChooseWeight(const Rgb8& c, const Endpoints& ends, int bits) {
  if (bits == 0) return 0;
  const double m = double((1u << bits) - 1);
  const double dr = ends.b.r - ends.a.r, dg = ends.b.g - ends.a.g, db = ends.b.b - ends.a.b;
  const double len2 = dr * dr + dg * dg + db * db;
  if (len2 == 0) return 0;
  const double t = ((c.r - ends.a.r) * dr + (c.g - ends.a.g) * dg + (c.b - ends.a.b) * db) / len2;
  return static_cast<uint32_t>(std::lround(std::clamp(t, 0.0, 1.0) * m));
}

BlockFit FitBlock(const Rgb8* colors, size_t n, int bits, double give_up_above) {
  Vec3 mean{};
  for (size_t i = 0; i < n; ++i) {
    const Vec3 c = ToVec(colors[i]);
    for (int k = 0; k < 3; ++k) mean[k] += c[k];
  }
  for (double& v : mean) v /= double(n);
  if (bits == 0 || n == 1) {
    const Endpoints ends{ToRgb(mean), ToRgb(mean)};
    return {ends, Sse(colors, n, ends, 0, give_up_above)};
  }
  // Principal axis of the colors by power iteration on their covariance.
  double cov[3][3] = {};
  for (size_t i = 0; i < n; ++i) {
    const Vec3 c = ToVec(colors[i]);
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) cov[j][k] += (c[j] - mean[j]) * (c[k] - mean[k]);
    }
  }
  Vec3 axis{1, 1, 1};
  for (int iter = 0; iter < 8; ++iter) {
    Vec3 next{};
    for (int j = 0; j < 3; ++j) next[j] = cov[j][0] * axis[0] + cov[j][1] * axis[1] + cov[j][2] * axis[2];
    const double norm = std::sqrt(next[0] * next[0] + next[1] * next[1] + next[2] * next[2]);
    if (norm < 1e-12) break;
    for (int j = 0; j < 3; ++j) axis[j] = next[j] / norm;
  }
  double lo = 0, hi = 0;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 c = ToVec(colors[i]);
    const double t = (c[0] - mean[0]) * axis[0] + (c[1] - mean[1]) * axis[1] + (c[2] - mean[2]) * axis[2];
    lo = std::min(lo, t), hi = std::max(hi, t);
  }
  Endpoints ends{ToRgb({mean[0] + lo * axis[0], mean[1] + lo * axis[1], mean[2] + lo * axis[2]}),
                 ToRgb({mean[0] + hi * axis[0], mean[1] + hi * axis[1], mean[2] + hi * axis[2]})};
  BlockFit best{ends, Sse(colors, n, ends, bits, 1e300)};
  Endpoints refined = ends;
  if (RefineEndpoints(colors, n, bits, refined)) {
    const double sse = Sse(colors, n, refined, bits, best.sse);
    if (sse < best.sse) best = {refined, sse};
  }
  return best;
}

}  // namespace pointdag
