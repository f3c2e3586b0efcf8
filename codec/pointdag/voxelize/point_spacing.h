// Stage 3a: a scan's point spacing, from which pointdagd derives a voxel size (ingest.h).
//
// Contract: for each point, the squared distance to its nearest other point, (dx² + dy²) + dz² in
// doubles; points with another point at distance 0 are left out; the result is the square root of
// the median (the upper one for an even count) of the rest, 0 when no point is left (or a
// coordinate is not finite). Exact, as a k-d tree's search is: a uniform grid of cells about two
// points each, each point compared with the cells about its own that could hold a nearer point,
// further shells of cells only for the rare isolated point (and every point for the rarest); the
// points' searches split over two threads.
#pragma once

#include <array>
#include <span>

namespace pointdag {

double MedianPointSpacing(std::span<const std::array<double, 3>> points);

}  // namespace pointdag
