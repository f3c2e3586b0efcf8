// Which decoded voxels predict each color of the lossless coder (lossless_predict.h): the
// neighbours within ±2 (±4 for a voxel with few), and in column mode the columns around it. They
// depend on the voxels alone, not on their colors or channel order, so the encoder's layout trials
// (lossless_layout.h) find them once and replay them.
#pragma once

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

  // Voxel i's neighbourhood, valid until the next call; the voxels in order, each once. In column
  // mode the columns' voxels follow the box's: the first `box` found are those without columns.
  Neighbourhood Next(size_t i, size_t* box = nullptr);

  // From here on without the columns (a column trial lost).
  void DropColumns() { columns_.reset(); }

 private:
  // The found voxels, up to the ±4 box and the columns within ±6.
  void Add(size_t j, int d2) {
    if (n_ < found_.size()) found_[n_++] = {static_cast<uint32_t>(j), static_cast<uint32_t>(d2)};
  }

  int version_;
  CausalNeighbours neighbours_;
  std::optional<CausalColumns> columns_;
  std::array<Neighbour, 9 * 9 * 9 - 1 + 13 * 13> found_{};  // a member: not cleared per voxel
  size_t n_ = 0;
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
    return {all, v.reach, false};
  }

 private:
  struct Voxel {
    size_t begin, box, end;
    bool reach;
  };
  std::vector<Neighbour> found_;
  std::vector<Voxel> voxels_;
};

}  // namespace pointdag::lossless
