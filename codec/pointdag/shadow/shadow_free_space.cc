// The free-space mode of the shadow DAG (ShadowBuildOptions::define_free_space): every cell whose
// centre lies outside the voxel cubes is defined with its true answer, so points in the air get one
// too, not only the surfaces.
//
// A light-space depth map of the voxel cubes: along the line through each column's cell centres
// (parallel to the travel), the first run of cubes the light meets ends at `exit`. A free cell
// before the run is lit (nothing on its way to the light), after it shadowed (its ray crosses the
// run); cells whose centre is inside the run are inside geometry, undefined, and take the same
// step, lit before the first cell whose centre lies past `exit`. So each column is one step, and
// the voxel-centre cells whose exact answer (voxel_shadows.h) differs from their column's step are
// kept as exceptions. The grid is then built top-down: a node whose columns all step before (after)
// its z' range and that holds no exception is all shadowed (lit) and never opened; the rest goes
// down to bricks. Work and memory: the cubes' column segments (about 20 per voxel at
// light_depth = depth + 2), plus the nodes on the steps' surface.
#include <algorithm>
#include <cmath>

#include "pointdag/shadow/shadow_dag_impl.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

constexpr uint64_t Spread2(uint32_t v) {
  uint64_t x = v;
  x = (x | x << 16) & 0x0000FFFF0000FFFFull;
  x = (x | x << 8) & 0x00FF00FF00FF00FFull;
  x = (x | x << 4) & 0x0F0F0F0F0F0F0F0Full;
  x = (x | x << 2) & 0x3333333333333333ull;
  x = (x | x << 1) & 0x5555555555555555ull;
  return x;
}

// A column's 2D Morton code (x' high), so a node's columns are one contiguous range.
constexpr uint64_t Column(uint32_t x, uint32_t y) { return Spread2(x) << 1 | Spread2(y); }

// A brick cell's (6 low Morton bits) column among the brick's 16 (4 low column bits) and its z'.
constexpr auto kBrickColumn = [] {
  std::array<uint8_t, 64> t{};
  for (uint32_t b = 0; b < 64; ++b) t[b] = static_cast<uint8_t>(Column(MortonDecode(b)[0], MortonDecode(b)[1]));
  return t;
}();
constexpr auto kBrickZ = [] {
  std::array<uint8_t, 64> t{};
  for (uint32_t b = 0; b < 64; ++b) t[b] = static_cast<uint8_t>(MortonDecode(b)[2]);
  return t;
}();

// The part of sorted[lo, hi) whose keys (entry >> shift) lie in [from, to).
std::pair<size_t, size_t> SubRange(const std::vector<uint64_t>& sorted, size_t lo, size_t hi, uint64_t from, uint64_t to,
                                   int shift) {
  const auto less = [shift](uint64_t entry, uint64_t key) { return (entry >> shift) < key; };
  const auto begin = sorted.begin() + static_cast<long>(lo), end = sorted.begin() + static_cast<long>(hi);
  const auto first = std::lower_bound(begin, end, from, less);
  const auto last = std::lower_bound(first, end, to, less);
  return {static_cast<size_t>(first - sorted.begin()), static_cast<size_t>(last - sorted.begin())};
}

struct Segment {
  uint64_t column;
  double in, out;  // along z', from the light cube's near face
};

class FreeSpaceBuild {
 public:
  FreeSpaceBuild(const LightFrame& frame, ShadowSubtreeSink& sink)
      : frame_(frame), sink_(sink), side_(uint32_t{1} << frame.light_depth()) {}

  // Steps of every column some cube crosses; the others never step (all lit).
  void Steps(const Svdag& dag) {
    const auto& axes = frame_.axes();
    const double s = frame_.cell_size(), h = frame_.half_side(), half_grid = std::ldexp(0.5, frame_.depth());
    std::array<double, 2> extent{};
    for (int a = 0; a < 2; ++a) extent[a] = 0.5 * (std::abs(axes[a][0]) + std::abs(axes[a][1]) + std::abs(axes[a][2]));
    std::vector<Segment> segments;
    dag.ForEachVoxel([&](uint64_t morton) {
      const auto k = MortonDecode(morton);
      std::array<uint32_t, 2> lo{}, hi{};
      for (int a = 0; a < 2; ++a) {
        double q = h;
        for (int j = 0; j < 3; ++j) q += axes[a][j] * (k[j] + 0.5 - half_grid);
        lo[a] = static_cast<uint32_t>(std::clamp(std::ceil((q - extent[a]) / s - 0.5), 0.0, double(side_ - 1)));
        hi[a] = static_cast<uint32_t>(std::clamp(std::floor((q + extent[a]) / s - 0.5), 0.0, double(side_ - 1)));
      }
      for (uint32_t i = lo[0]; i <= hi[0]; ++i) {
        for (uint32_t j = lo[1]; j <= hi[1]; ++j) {
          const auto origin = frame_.GridPoint({(i + 0.5) * s, (j + 0.5) * s, 0});
          double in = -1e300, out = 1e300;
          for (int c = 0; c < 3 && in <= out; ++c) {
            const double d = axes[2][c];
            if (std::abs(d) < 1e-12) {
              if (origin[c] < k[c] || origin[c] > k[c] + 1.0) in = 1e300;
              continue;
            }
            double a = (k[c] - origin[c]) / d, b = (k[c] + 1.0 - origin[c]) / d;
            if (a > b) std::swap(a, b);
            in = std::max(in, a);
            out = std::min(out, b);
          }
          if (in <= out) segments.push_back({Column(i, j), in, out});
        }
      }
    });
    std::sort(segments.begin(), segments.end(),
              [](const Segment& a, const Segment& b) { return a.column != b.column ? a.column < b.column : a.in < b.in; });
    for (size_t at = 0; at < segments.size();) {
      double exit = segments[at].out;
      size_t next = at + 1;
      for (; next < segments.size() && segments[next].column == segments[at].column; ++next) {
        if (segments[next].in <= exit) exit = std::max(exit, segments[next].out);
      }
      // The first cell whose centre lies past the run; a later segment that starts past `exit` only
      // matters behind it, where everything is shadowed already.
      const double first = std::floor(exit / s - 0.5) + 1;
      columns_.push_back(segments[at].column);
      steps_.push_back(static_cast<uint32_t>(std::clamp(first, 0.0, double(side_))));
      at = next;
    }
    peak_bytes_ = segments.capacity() * sizeof(Segment);
    // Per height, the least and greatest step and the count of crossed columns of every footprint.
    pyramid_.resize(frame_.light_depth() + 1);
    for (int height = 0; height <= frame_.light_depth(); ++height) {
      Footprints& level = pyramid_[height];
      for (size_t i = 0; i < columns_.size(); ++i) {
        const uint64_t prefix = columns_[i] >> (2 * height);
        if (level.prefix.empty() || level.prefix.back() != prefix) {
          level.prefix.push_back(prefix);
          level.min.push_back(steps_[i]);
          level.max.push_back(steps_[i]);
          level.count.push_back(0);
        }
        level.min.back() = std::min(level.min.back(), steps_[i]);
        level.max.back() = std::max(level.max.back(), steps_[i]);
        ++level.count.back();
      }
      peak_bytes_ += level.prefix.capacity() * 20;
    }
  }

  // The centre cells (code << 1 | shadowed, sorted) whose answer is not their column's step.
  void Exceptions(std::span<const uint64_t> cells) {
    for (uint64_t cell : cells) {
      const auto [x, y, z] = MortonDecode(cell >> 1);
      if ((z >= StepAt(x, y)) != ((cell & 1) != 0)) exceptions_.push_back(cell);
    }
  }

  void Build(ShadowDag::Impl& out) {
    Node(frame_.light_depth(), {0, 0, 0}, 0, columns_.size(), 0, exceptions_.size());
    sink_.Finish(out);
    out.stats.build_peak_bytes += peak_bytes_ + columns_.capacity() * 12 + exceptions_.capacity() * 8;
  }

 private:
  uint32_t StepAt(uint32_t x, uint32_t y) const {
    const uint64_t column = Column(x, y);
    const auto it = std::lower_bound(columns_.begin(), columns_.end(), column);
    return it != columns_.end() && *it == column ? steps_[static_cast<size_t>(it - columns_.begin())] : side_;
  }

  // The subtree of `height` with minimum corner `corner`; its columns are columns_[clo, chi), its
  // exceptions exceptions_[elo, ehi).
  void Node(int height, std::array<uint32_t, 3> corner, size_t clo, size_t chi, size_t elo, size_t ehi) {
    const uint32_t size = uint32_t{1} << height;
    const uint64_t key = MortonEncode(corner[0] >> height, corner[1] >> height, corner[2] >> height);
    uint32_t min_step = side_, max_step = side_;  // columns no cube crosses never step
    const Footprints& level = pyramid_[height];
    const uint64_t prefix = Column(corner[0] >> height, corner[1] >> height);
    const auto at = std::lower_bound(level.prefix.begin(), level.prefix.end(), prefix);
    if (at != level.prefix.end() && *at == prefix) {
      const size_t i = static_cast<size_t>(at - level.prefix.begin());
      min_step = level.min[i];
      if (level.count[i] == uint64_t{size} * size) max_step = level.max[i];
    }
    if (elo == ehi && max_step <= corner[2]) return sink_.Uniform(height, key, true);
    if (elo == ehi && min_step >= corner[2] + size) return sink_.Uniform(height, key, false);
    if (height == 2) {
      std::array<uint32_t, 16> step;  // by the column's 4 low bits (x<<1|y interleaved)
      step.fill(side_);
      for (size_t i = clo; i < chi; ++i) step[columns_[i] & 15] = steps_[i];
      uint64_t mask = 0;
      for (uint32_t b = 0; b < 64; ++b) mask |= uint64_t{corner[2] + kBrickZ[b] >= step[kBrickColumn[b]]} << b;
      for (size_t e = elo; e < ehi; ++e) {
        const uint64_t bit = uint64_t{1} << ((exceptions_[e] >> 1) & 63);
        mask = (exceptions_[e] & 1) ? mask | bit : mask & ~bit;
      }
      return sink_.Brick(key, mask);
    }
    const uint32_t half = size / 2;
    for (uint32_t octant = 0; octant < 8; ++octant) {
      const std::array<uint32_t, 3> c{corner[0] + ((octant >> 2) & 1) * half, corner[1] + ((octant >> 1) & 1) * half,
                                      corner[2] + (octant & 1) * half};
      const int below = height - 1;
      const uint64_t column = Column(c[0] >> below, c[1] >> below);
      const auto [c0, c1] = SubRange(columns_, clo, chi, column << (2 * below), (column + 1) << (2 * below), 0);
      const uint64_t cell = MortonEncode(c[0] >> below, c[1] >> below, c[2] >> below);
      const auto [e0, e1] = SubRange(exceptions_, elo, ehi, cell << (3 * below), (cell + 1) << (3 * below), 1);
      Node(below, c, c0, c1, e0, e1);
    }
  }

  const LightFrame& frame_;
  ShadowSubtreeSink& sink_;
  uint32_t side_;
  std::vector<uint64_t> columns_;  // sorted
  std::vector<uint32_t> steps_;    // per column: the first cell index (z') that is shadowed
  std::vector<uint64_t> exceptions_;
  struct Footprints {
    std::vector<uint64_t> prefix;  // sorted
    std::vector<uint32_t> min, max, count;
  };
  std::vector<Footprints> pyramid_;
  uint64_t peak_bytes_ = 0;
};

}  // namespace

Status BuildFreeSpaceArrays(const Svdag& dag, std::span<const uint64_t> centre_cells, const ShadowBuildOptions& options,
                            ShadowDag::Impl& out) {
  ShadowSubtreeSink sink(out.frame.light_depth(), options);
  FreeSpaceBuild build(out.frame, sink);
  build.Steps(dag);
  build.Exceptions(centre_cells);
  build.Build(out);
  return Status::Ok();
}

}  // namespace pointdag
