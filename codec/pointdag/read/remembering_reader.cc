#include "pointdag/read/remembering_reader.h"

#include <algorithm>

namespace pointdag {

RememberingReader::RememberingReader(std::unique_ptr<ScanReader> inner, uint64_t max_points)
    : inner_(std::move(inner)), max_points_(max_points) {
  info_ = inner_->info();
  max_color_seen_ = inner_->max_color_seen();
}

StatusOr<size_t> RememberingReader::Read(PointBatch& batch, size_t max_points) {
  if (keeping_ && next_ < kept_.size()) {
    const size_t n = std::min(max_points, kept_.size() - next_);
    const auto first = static_cast<std::ptrdiff_t>(next_), last = static_cast<std::ptrdiff_t>(next_ + n);
    batch.xyz.assign(kept_.xyz.begin() + first, kept_.xyz.begin() + last);
    batch.rgb.clear();
    if (!kept_.rgb.empty()) batch.rgb.assign(kept_.rgb.begin() + first, kept_.rgb.begin() + last);
    next_ += n;
    return n;
  }
  if (keeping_ && complete_) {
    batch.clear();
    return size_t{0};
  }
  ASSIGN_OR_RETURN(const size_t n, inner_->Read(batch, max_points));
  info_ = inner_->info();
  max_color_seen_ = inner_->max_color_seen();
  if (!keeping_) return n;
  if (n == 0) {
    complete_ = true;
  } else if (kept_.size() + n > max_points_) {
    keeping_ = false;
    kept_ = PointBatch{};  // frees the memory
  } else {
    kept_.xyz.insert(kept_.xyz.end(), batch.xyz.begin(), batch.xyz.end());
    kept_.rgb.insert(kept_.rgb.end(), batch.rgb.begin(), batch.rgb.end());
    next_ = kept_.size();
  }
  return n;
}

Status RememberingReader::Rewind() {
  next_ = 0;
  // While keeping, the wrapped reader stays where the kept points end: a pass continues from there.
  return keeping_ ? Status::Ok() : inner_->Rewind();
}

}  // namespace pointdag
