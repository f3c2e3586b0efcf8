// Which decoded voxels predict each color of the lossless coder (lossless_predict.h): the
// neighbours within ±2 (±4 for a voxel with few), and in column mode the columns around it. They
// depend on the voxels alone, not on their colors or channel order, so the encoder's layout trials
// (lossless_layout.h) find them once and replay them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "pointdag/color/causal_columns.h"
#include "pointdag/color/causal_neighbours.h"
#include "pointdag/color/lossless_predict.h"

namespace pointdag::lossless {

class NeighbourhoodSearch {
 public:
  // `morton`: one code per color, sorted and unique; must outlive this. `columns`: version 4's
  // column mode (version 3 and up).
  NeighbourhoodSearch(std::span<const uint64_t> morton, int version, bool columns);

  // How many of a neighbourhood's found and adjacent voxels the box gave.
  struct BoxCounts {
    size_t found = 0, adjacent = 0;
  };
  // Voxel i's neighbourhood, valid until the next call; the voxels in order, each once. In column
  // mode the columns' voxels follow the box's in both lists: `box` counts those without columns.
  Neighbourhood Next(size_t i, BoxCounts* box = nullptr);

  // From here on without the columns (a column trial lost).
  void DropColumns() { columns_.reset(); }

 private:
  // The found voxels, up to the ±4 box and the columns within ±6.
  void Add(size_t j, int d2) {
    if (n_ == found_.size()) return;
    found_[n_++] = {static_cast<uint32_t>(j), static_cast<uint32_t>(d2)};
    if (d2 <= kAdjacent) adjacent_[adjacent_n_++] = found_[n_ - 1];
  }
  static constexpr int kAdjacent = 3;  // d2 of the 26 adjacent voxels, and of the 5 nearest columns' (d2 1 or 3)

  int version_;
  CausalNeighbours neighbours_;
  std::optional<CausalColumns> columns_;
  std::array<Neighbour, 9 * 9 * 9 - 1 + 13 * 13> found_{};  // a member: not cleared per voxel
  size_t n_ = 0;
  std::array<Neighbour, 26 + 5> adjacent_{};
  size_t adjacent_n_ = 0;
};

// The neighbourhoods of the first voxels, with and without the columns, found once for the
// encoder's trials.
class RecordedNeighbourhoods {
 public:
  // Voxels [0, count) of `search` (column mode), which goes on from voxel `count`.
  RecordedNeighbourhoods(NeighbourhoodSearch& search, size_t count);

  Neighbourhood At(size_t i, bool columns) const {
    const Voxel& v = voxels_[i];
    const std::span<const Neighbour> all(found_.data() + v.begin, (columns ? v.end : v.box) - v.begin);
    const std::span<const Neighbour> adjacent(adjacent_.data() + v.adjacent_begin,
                                              (columns ? v.adjacent_end : v.adjacent_box) - v.adjacent_begin);
    return {all, adjacent, v.reach, false};
  }

 private:
  struct Voxel {
    size_t begin, box, end;
    size_t adjacent_begin, adjacent_box, adjacent_end;
    bool reach;
  };
  std::vector<Neighbour> found_, adjacent_;
  std::vector<Voxel> voxels_;
};

}  // namespace pointdag::lossless
