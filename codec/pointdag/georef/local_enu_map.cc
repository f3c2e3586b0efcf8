#include "pointdag/georef/local_enu_map.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace pointdag {
namespace {

// Fit grid: 9 x 9 across the box, 3 heights; check grid: 17 x 17 x 5, which holds every point
// halfway between fit nodes.
constexpr int kFitSide = 9, kFitHeights = 3, kCheckSide = 17, kCheckHeights = 5;

double Node(int i, int n) { return -1.0 + 2.0 * i / (n - 1); }

// The basis's terms in its order, each handed to `use`: u^i v^(d-i) w^k, d up to 4, 3, 1 for k = 0, 1, 2.
template <class Use>
void ForEachTerm(double u, double v, double w, Use&& use) {
  const double up[5] = {1, u, u * u, u * u * u, u * u * u * u};
  const double vp[5] = {1, v, v * v, v * v * v, v * v * v * v};
  const double wp[3] = {1, w, w * w};
  constexpr int kMaxUvDegree[3] = {4, 3, 1};  // by the power of w
  for (int k = 0; k < 3; ++k) {
    for (int d = 0; d <= kMaxUvDegree[k]; ++d) {
      for (int i = d; i >= 0; --i) use(up[i] * vp[d - i] * wp[k]);
    }
  }
}

}  // namespace

std::array<double, LocalEnuMap::kTerms> LocalEnuMap::Basis(double u, double v, double w) {
  std::array<double, kTerms> out{};
  int n = 0;
  ForEachTerm(u, v, w, [&](double term) { out[n++] = term; });
  return out;
}

std::optional<LocalEnuMap> LocalEnuMap::Fit(const Bounds& box, const ExactFn& exact, double tolerance_m) {
  LocalEnuMap map;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(box.min[a]) || !std::isfinite(box.max[a]) || box.max[a] < box.min[a]) return std::nullopt;
    map.centre_[a] = (box.min[a] + box.max[a]) / 2;
    // A flat axis still needs a span to sample: one source unit.
    map.half_[a] = std::max((box.max[a] - box.min[a]) / 2, 0.5);
  }
  const auto grid = [&](int side, int heights) {
    std::vector<std::array<double, 3>> scaled, source;
    for (int k = 0; k < heights; ++k) {
      for (int j = 0; j < side; ++j) {
        for (int i = 0; i < side; ++i) {
          const std::array<double, 3> s = {Node(i, side), Node(j, side), Node(k, heights)};
          scaled.push_back(s);
          source.push_back({map.centre_[0] + s[0] * map.half_[0], map.centre_[1] + s[1] * map.half_[1],
                            map.centre_[2] + s[2] * map.half_[2]});
        }
      }
    }
    return std::pair{scaled, source};
  };

  auto [fit_scaled, fit_enu] = grid(kFitSide, kFitHeights);
  if (!exact(fit_enu).ok()) return std::nullopt;
  Eigen::MatrixXd a(fit_scaled.size(), kTerms);
  Eigen::MatrixXd b(fit_scaled.size(), 3);
  for (size_t r = 0; r < fit_scaled.size(); ++r) {
    const auto basis = Basis(fit_scaled[r][0], fit_scaled[r][1], fit_scaled[r][2]);
    for (int c = 0; c < kTerms; ++c) a(static_cast<Eigen::Index>(r), c) = basis[c];
    for (int c = 0; c < 3; ++c) b(static_cast<Eigen::Index>(r), c) = fit_enu[r][c];
  }
  const Eigen::MatrixXd x = a.colPivHouseholderQr().solve(b);
  for (int c = 0; c < 3; ++c) {
    for (int t = 0; t < kTerms; ++t) map.coefficients_[c][t] = x(t, c);
  }

  auto [check_scaled, check_enu] = grid(kCheckSide, kCheckHeights);
  std::vector<std::array<double, 3>> check_source = check_enu;
  if (!exact(check_enu).ok()) return std::nullopt;
  for (size_t r = 0; r < check_source.size(); ++r) {
    const std::array<double, 3> mapped = map.Evaluate(check_source[r]);
    const double error = std::hypot(mapped[0] - check_enu[r][0], mapped[1] - check_enu[r][1], mapped[2] - check_enu[r][2]);
    if (!(error <= tolerance_m)) return std::nullopt;  // NaN too
    map.max_error_m_ = std::max(map.max_error_m_, error);
  }
  return map;
}

// The three sums term by term as the terms come: no basis array in between (half the time a
// point; every sum adds the same products in the same order as before, so the same bits).
std::array<double, 3> LocalEnuMap::Evaluate(const std::array<double, 3>& p) const {
  double e = 0, n = 0, u = 0;
  int t = 0;
  ForEachTerm((p[0] - centre_[0]) / half_[0], (p[1] - centre_[1]) / half_[1], (p[2] - centre_[2]) / half_[2], [&](double term) {
    e += coefficients_[0][t] * term;
    n += coefficients_[1][t] * term;
    u += coefficients_[2][t] * term;
    ++t;
  });
  return {e, n, u};
}

bool LocalEnuMap::Inside(const std::array<double, 3>& p) const {
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(p[a] - centre_[a]) <= half_[a])) return false;  // NaN is outside
  }
  return true;
}

void LocalEnuMap::Apply(std::span<std::array<double, 3>> points, std::vector<size_t>& outside) const {
  outside.clear();
  for (size_t i = 0; i < points.size(); ++i) {
    if (Inside(points[i])) {
      points[i] = Evaluate(points[i]);
    } else {
      outside.push_back(i);
    }
  }
}

}  // namespace pointdag
