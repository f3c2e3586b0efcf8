// A ScanReader that keeps a small scan's points as it first reads them, so that the passes after
// the first (the spacing sample, the survey, the voxelizer's second pass: IngestScan reads its
// scan's first points three times) are served from memory instead of parsed and georeferenced
// again. Past `max_points` the points are dropped and later passes read the wrapped reader again.
// The same points, in the same order, come out either way.
#pragma once

#include <memory>

#include "pointdag/read/scan_reader.h"

namespace pointdag {

class RememberingReader final : public ScanReader {
 public:
  RememberingReader(std::unique_ptr<ScanReader> inner, uint64_t max_points);

  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override;
  Status Rewind() override;

 private:
  std::unique_ptr<ScanReader> inner_;
  uint64_t max_points_;
  PointBatch kept_;        // the scan's first points; inner_ stands right after them while keeping_
  bool keeping_ = true;    // false once the scan outgrew max_points (kept_ is then empty)
  bool complete_ = false;  // kept_ is the whole scan
  size_t next_ = 0;        // this pass's next point, while it is served from kept_
};

}  // namespace pointdag
