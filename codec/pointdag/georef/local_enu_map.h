// A polynomial stand-in for the exact source CRS -> ENU transform over one box of source
// coordinates (the scan's bounds), used because the exact path (PROJ's inverse projection and
// datum shift, then GeographicLib's ENU) costs ~1-2 µs a point, a third of a georeferenced ingest.
//
// Contract: Fit() samples the exact transform on a grid over the box, fits each ENU axis by least
// squares (degree 4 across the box, 3 with one power of height, 1 with its square: a projected
// CRS's map is smooth and ENU is nearly linear in height), then checks the fit against the exact
// transform on a grid twice as fine, offset from the first. It returns nullopt (keep the exact path)
// when any sample fails or the worst error exceeds `tolerance_m`; otherwise max_error_m() is that
// worst error. Apply() maps the points inside the box and leaves the others untouched, saying which.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "pointdag/read/scan_reader.h"
#include "pointdag/status.h"

namespace pointdag {

class LocalEnuMap {
 public:
  // The exact transform, in place (source units in, ENU metres out).
  using ExactFn = std::function<Status(std::span<std::array<double, 3>>)>;
  static constexpr int kTerms = 28;

  static std::optional<LocalEnuMap> Fit(const Bounds& box, const ExactFn& exact, double tolerance_m);

  double max_error_m() const { return max_error_m_; }
  // Maps the points inside the box; `outside` gets the indices of the others (cleared first).
  void Apply(std::span<std::array<double, 3>> points, std::vector<size_t>& outside) const;

 private:
  LocalEnuMap() = default;
  // The basis at a point already scaled to [-1, 1]^3.
  static std::array<double, kTerms> Basis(double u, double v, double w);
  std::array<double, 3> Evaluate(const std::array<double, 3>& p) const;
  bool Inside(const std::array<double, 3>& p) const;

  std::array<double, 3> centre_{}, half_{};
  std::array<std::array<double, kTerms>, 3> coefficients_{};
  double max_error_m_ = 0;
};

}  // namespace pointdag
