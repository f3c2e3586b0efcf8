#include "pointdag/voxelize/point_spacing.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <thread>
#include <vector>

#include "pointdag/voxelize/radix_sort.h"

namespace pointdag {
namespace {

using Point = std::array<double, 3>;
using CellXyz = std::array<int64_t, 3>;

constexpr int64_t kMaxCell = (int64_t{1} << 21) - 1;  // per axis
constexpr int kMaxShell = 6;  // an isolated point not settled within this many shells is compared with every point

double SquaredDistance(const Point& a, const Point& b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

// Cells of `cell` a side from `lo`, numbered x-major within the box of `count` cells a side.
class Grid {
 public:
  Grid(Point lo, double cell, CellXyz count = {1, 1, 1}) : lo_(lo), cell_(cell), count_(count) {}

  CellXyz CellOf(const Point& p) const {
    CellXyz c;
    // p >= lo_ for the grid's own points: truncation is floor there (and clamps the rest).
    for (int k = 0; k < 3; ++k) c[k] = std::clamp<int64_t>(static_cast<int64_t>((p[k] - lo_[k]) / cell_), 0, kMaxCell);
    return c;
  }
  double Low(int k, int64_t c) const { return lo_[k] + static_cast<double>(c) * cell_; }
  double cell() const { return cell_; }
  bool Inside(const CellXyz& c) const {
    return c[0] >= 0 && c[0] < count_[0] && c[1] >= 0 && c[1] < count_[1] && c[2] >= 0 && c[2] < count_[2];
  }
  uint64_t Index(const CellXyz& c) const { return static_cast<uint64_t>((c[0] * count_[1] + c[1]) * count_[2] + c[2]); }
  int64_t count(int k) const { return count_[k]; }

 private:
  Point lo_;
  double cell_;
  CellXyz count_;
};

// Cells that hold about two points each where the points lie: the cube root of the bounding box's
// volume per point, shrunk by the square root of the points per occupied cell found there (a scan
// is mostly surfaces: a cell's points grow with its area). The cells are counted in a hash set.
double CellSize(std::span<const Point> points, const Point& lo, double extent) {
  const double finest = extent / static_cast<double>(kMaxCell - 1);
  double cell = std::max(extent / std::cbrt(static_cast<double>(points.size())), finest);
  const Grid grid(lo, cell);
  const int bits = static_cast<int>(std::bit_width(2 * points.size() - 1));
  std::vector<uint64_t> slots(size_t{1} << bits, ~uint64_t{0});
  size_t distinct = 0;
  for (const Point& p : points) {
    const CellXyz c = grid.CellOf(p);
    const uint64_t key = (static_cast<uint64_t>(c[0]) << 42) | (static_cast<uint64_t>(c[1]) << 21) | static_cast<uint64_t>(c[2]);
    size_t s = static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
    while (slots[s] != key && slots[s] != ~uint64_t{0}) s = (s + 1) & (slots.size() - 1);
    if (slots[s] != key) slots[s] = key, ++distinct;
  }
  const double per_cell = static_cast<double>(points.size()) / static_cast<double>(distinct);
  if (per_cell > 2) cell = std::max(cell * std::sqrt(2 / per_cell), finest);
  return cell;
}

// The points sorted by cell index, and each occupied cell's run of them.
struct Cells {
  Grid grid;
  double slack;                     // what every computed bound is widened by
  std::vector<Point> sorted;
  std::vector<uint64_t> run_index;  // each run's cell index, ascending
  std::vector<uint32_t> run_begin;  // where each run starts in `sorted`, then the point count

  // p's nearest other point in `run`, where nearer than `best`.
  void Visit(uint32_t i, size_t run, double& best) const {
    const Point& p = sorted[i];
    for (uint32_t j = run_begin[run]; j < run_begin[run + 1]; ++j) {
      if (j != i) best = std::min(best, SquaredDistance(p, sorted[j]));
    }
  }

  // The rare point whose nearest other point may lie beyond the 3x3x3 cells about home (already
  // searched for anything nearer than `best`): further shells of cells, then every point.
  double FarNearest(uint32_t i, const CellXyz& home, double best) const {
    const Point& p = sorted[i];
    for (int64_t s = 2; s <= kMaxShell; ++s) {
      for (int64_t dx = -s; dx <= s; ++dx) {
        for (int64_t dy = -s; dy <= s; ++dy) {
          const bool side = std::max(std::abs(dx), std::abs(dy)) == s;
          for (int64_t dz = -s; dz <= s; dz += side ? 1 : 2 * s) {
            const CellXyz c = {home[0] + dx, home[1] + dy, home[2] + dz};
            if (!grid.Inside(c)) continue;
            double gap2 = 0;  // from p to the cell's box, less the slack
            for (int k = 0; k < 3; ++k) {
              const double gap = std::max({grid.Low(k, c[k]) - p[k], p[k] - grid.Low(k, c[k] + 1), 0.0}) - slack;
              if (gap > 0) gap2 += gap * gap;
            }
            if (gap2 >= best) continue;
            const auto run = std::lower_bound(run_index.begin(), run_index.end(), grid.Index(c));
            if (run != run_index.end() && *run == grid.Index(c)) Visit(i, static_cast<size_t>(run - run_index.begin()), best);
          }
        }
      }
      double covered = std::numeric_limits<double>::infinity();  // every point this near lies within shell s
      for (int k = 0; k < 3; ++k) {
        covered = std::min({covered, p[k] - grid.Low(k, home[k] - s), grid.Low(k, home[k] + s + 1) - p[k]});
      }
      covered -= slack;
      if (best == 0 || (covered > 0 && best <= covered * covered)) return best;
    }
    for (uint32_t j = 0; j < sorted.size(); ++j) {
      if (j != i) best = std::min(best, SquaredDistance(p, sorted[j]));
    }
    return best;
  }

  // The squared nearest distances of the points of runs [first, end), 0s left out, onto `nearest`.
  void Nearest(size_t first, size_t end, std::vector<double>& nearest) const {
    // The runs of the 3x3x3 cells about home, at (dx + 1) * 9 + (dy + 1) * 3 + dz + 1 (-1: empty).
    // The runs are in cell index order and so are the homes: each of the nine columns about home
    // is found from where it was for the previous home, a cursor that only moves forward.
    std::array<int64_t, 27> around;
    std::array<size_t, 9> cursor;
    cursor.fill(first > 0 ? first - 1 : 0);
    const double cell = grid.cell();
    for (size_t run = first; run < end; ++run) {
      const CellXyz home = grid.CellOf(sorted[run_begin[run]]);
      around.fill(-1);
      for (int column = 0; column < 9; ++column) {
        const CellXyz low = {home[0] + column / 3 - 1, home[1] + column % 3 - 1, std::max<int64_t>(home[2] - 1, 0)};
        if (!grid.Inside(low)) continue;
        const uint64_t from = grid.Index(low), to = grid.Index({low[0], low[1], std::min(home[2] + 1, grid.count(2) - 1)});
        size_t& c = cursor[static_cast<size_t>(column)];
        while (c > 0 && run_index[c - 1] >= from) --c;  // a cursor starts a little behind (from `first - 1`)
        while (c < run_index.size() && run_index[c] < from) ++c;
        for (size_t r = c; r < run_index.size() && run_index[r] <= to; ++r) {
          around[static_cast<size_t>(column * 3 + 1 + static_cast<int64_t>(run_index[r] - grid.Index({low[0], low[1], home[2]})))] =
              static_cast<int64_t>(r);
        }
      }
      const Point base = {grid.Low(0, home[0]), grid.Low(1, home[1]), grid.Low(2, home[2])};
      for (uint32_t i = run_begin[run]; i < run_begin[run + 1]; ++i) {
        const Point& p = sorted[i];
        double best = std::numeric_limits<double>::infinity();
        Visit(i, run, best);
        // Squared gaps to the slabs of cells below, at and above home along each axis (less the
        // slack); every point within `covered` of p lies in the 3x3x3 cells about home.
        std::array<std::array<double, 3>, 3> gap2;
        double covered = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k) {
          const double below = p[k] - base[k], above = base[k] + cell - p[k];
          const double b = std::max(below - slack, 0.0), a = std::max(above - slack, 0.0);
          gap2[k] = {b * b, 0.0, a * a};
          covered = std::min({covered, below, above});
        }
        covered += cell - slack;
        std::array<int, 3> lo, hi;  // along each axis, only the sides nearer than the best so far
        for (int k = 0; k < 3; ++k) lo[k] = gap2[k][0] < best ? 0 : 1, hi[k] = gap2[k][2] < best ? 2 : 1;
        for (int x = lo[0]; x <= hi[0]; ++x) {
          for (int y = lo[1]; y <= hi[1]; ++y) {
            for (int z = lo[2]; z <= hi[2]; ++z) {
              const int64_t r = around[static_cast<size_t>(x * 9 + y * 3 + z)];
              if (r >= 0 && static_cast<size_t>(r) != run && gap2[0][x] + gap2[1][y] + gap2[2][z] < best) {
                Visit(i, static_cast<size_t>(r), best);
              }
            }
          }
        }
        if (best != 0 && !(covered > 0 && best <= covered * covered)) best = FarNearest(i, home, best);
        if (best > 0) nearest.push_back(best);
      }
    }
  }
};

}  // namespace

double MedianPointSpacing(std::span<const Point> points) {
  const size_t n = points.size();
  if (n < 2) return 0.0;
  Point lo = points[0], hi = points[0];
  for (const Point& p : points) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  if (!(extent > 0) || !std::isfinite(extent)) return 0.0;  // all points coincide (or are not numbers)
  const double cell = CellSize(points, lo, extent);
  const CellXyz last = Grid(lo, cell).CellOf(hi);
  const Grid grid(lo, cell, {last[0] + 1, last[1] + 1, last[2] + 1});

  struct Keyed {
    uint64_t index;
    uint32_t point;
  };
  std::vector<Keyed> keyed(n);
  for (size_t i = 0; i < n; ++i) keyed[i] = {grid.Index(grid.CellOf(points[i])), static_cast<uint32_t>(i)};
  RadixSortInPlace(std::span<Keyed>(keyed), static_cast<int>(std::bit_width(grid.Index(last))),
                   [](const Keyed& k) { return k.index; });
  // Cells are compared with distances through differences of large coordinates: widen every bound
  // by far more than their rounding (UTM northings near 1e7 m have ulps of 2e-9 m).
  const double magnitude = std::max({std::abs(lo[0]), std::abs(lo[1]), std::abs(lo[2])}) + extent;
  Cells cells{grid, cell * 1e-6 + magnitude * 1e-12, std::vector<Point>(n), {}, {}};
  for (size_t i = 0; i < n; ++i) {
    cells.sorted[i] = points[keyed[i].point];
    if (i == 0 || keyed[i].index != keyed[i - 1].index) {
      cells.run_index.push_back(keyed[i].index);
      cells.run_begin.push_back(static_cast<uint32_t>(i));
    }
  }
  cells.run_begin.push_back(static_cast<uint32_t>(n));
  const size_t runs = cells.run_index.size();

  // The second half of the points on a thread of its own (a plain thread: TSan sees its start and
  // join, not the uninstrumented libtbb's task edges) where there are enough to pay for it.
  std::vector<double> nearest, second_half;
  nearest.reserve(n);
  second_half.reserve(n / 2);
  size_t split = runs;
  if (n >= 4096) {
    split = static_cast<size_t>(std::lower_bound(cells.run_begin.begin(), cells.run_begin.end() - 1, n / 2) - cells.run_begin.begin());
  }
  std::thread second;
  if (split < runs) second = std::thread([&] { cells.Nearest(split, runs, second_half); });
  cells.Nearest(0, split, nearest);
  if (second.joinable()) second.join();
  nearest.insert(nearest.end(), second_half.begin(), second_half.end());
  if (nearest.empty()) return 0.0;
  const auto mid = nearest.begin() + static_cast<long>(nearest.size() / 2);
  std::nth_element(nearest.begin(), mid, nearest.end());
  return std::sqrt(*mid);
}

}  // namespace pointdag
