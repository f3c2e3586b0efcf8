// A ScanReader over points already in memory: synthetic scans in tests, decoded tiles in tools.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "pointdag/read/scan_reader.h"

namespace pointdag {

class MemoryScanReader final : public ScanReader {
 public:
  // `rgb` is empty for a scan without color, else parallel to `xyz`: 16-bit fields, which like LAS
  // may hold 8-bit values (the voxelizer tells which from the largest value).
  MemoryScanReader(std::vector<std::array<double, 3>> xyz, std::vector<std::array<uint16_t, 3>> rgb)
      : xyz_(std::move(xyz)), rgb_(std::move(rgb)) {
    info_.format = ScanFormat::kPly;
    info_.format_version = "memory";
    info_.point_count = xyz_.size();
    info_.has_color = !rgb_.empty();
    info_.stored_color_bits = 16;
  }

  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override {
    batch.clear();
    const size_t n = std::min(max_points, xyz_.size() - next_);
    for (size_t i = next_; i < next_ + n; ++i) {
      for (double v : xyz_[i]) {
        if (!std::isfinite(v)) return Malformed("point " + std::to_string(i) + " has a coordinate that is not finite");
      }
      batch.xyz.push_back(xyz_[i]);
      if (info_.has_color) {
        batch.rgb.push_back(rgb_[i]);
        for (uint16_t c : rgb_[i]) max_color_seen_ = std::max(max_color_seen_, c);
      }
    }
    next_ += n;
    return n;
  }

  Status Rewind() override {
    next_ = 0;
    return Status::Ok();
  }

 private:
  std::vector<std::array<double, 3>> xyz_;
  std::vector<std::array<uint16_t, 3>> rgb_;
  size_t next_ = 0;
};

}  // namespace pointdag
