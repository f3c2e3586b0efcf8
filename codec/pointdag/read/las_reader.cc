#include "pointdag/read/las_reader.h"

#include <string>

#include "pointdag/read/laz/laz_reader.h"

namespace pointdag {
namespace {

std::string Num(uint64_t v) { return std::to_string(v); }

}  // namespace

StatusOr<std::unique_ptr<ScanReader>> LasReader::Open(const std::filesystem::path& path) {
  std::error_code ec;
  const uint64_t file_size = std::filesystem::file_size(path, ec);
  if (ec) return IoError("cannot stat " + path.string() + ": " + ec.message());
  std::unique_ptr<LasReader> reader(new LasReader());
  reader->path_ = path.string();
  reader->file_ = std::fopen(reader->path_.c_str(), "rb");
  if (!reader->file_) return IoError("cannot open " + reader->path_);
  ASSIGN_OR_RETURN(reader->header_, ReadLasHeader(reader->file_, file_size, reader->info_, reader->layout_));
  const LasHeader& h = reader->header_;
  if (h.compressed) {
    ASSIGN_OR_RETURN(auto laz_reader, laz::LazReader::Open(path));
    return std::unique_ptr<ScanReader>(std::move(laz_reader));
  }
  const uint64_t available = (h.point_data_end - h.point_data_offset) / h.record_length;
  if (h.point_count == 0) return Malformed("LAS header declares zero points");
  if (h.point_count > available) {
    return Truncated("LAS header declares " + Num(h.point_count) + " points of " + Num(h.record_length) +
                     " bytes but the file holds only " + Num(available) + " complete records");
  }
  RETURN_IF_ERROR(reader->Rewind());
  return std::unique_ptr<ScanReader>(std::move(reader));
}

LasReader::~LasReader() {
  if (file_) std::fclose(file_);
}

Status LasReader::Rewind() {
  next_point_ = 0;
  if (fseeko(file_, static_cast<off_t>(header_.point_data_offset), SEEK_SET) != 0) {
    return IoError("cannot seek to the point data of " + path_);
  }
  return Status::Ok();
}

StatusOr<size_t> LasReader::Fill(size_t max_points) {
  const size_t n = static_cast<size_t>(std::min<uint64_t>(max_points, header_.point_count - next_point_));
  buffer_.resize(n * layout_.record_length);
  if (n > 0 && std::fread(buffer_.data(), layout_.record_length, n, file_) != n) {
    return Truncated("LAS point data ends early, at point " + Num(next_point_) + " of " + Num(header_.point_count));
  }
  return n;
}

StatusOr<size_t> LasReader::Read(PointBatch& batch, size_t max_points) {
  const StatusOr<size_t> n = Fill(max_points);
  if (!n.ok()) {
    batch.clear();
    return n.status();
  }
  // Resized, not cleared: a batch of the last call's size is overwritten without being zero-filled first.
  batch.xyz.resize(*n);
  batch.rgb.resize(layout_.rgb_offset != 0 ? *n : 0);
  RETURN_IF_ERROR(layout_.Decode(buffer_.data(), *n, next_point_, batch.xyz.data(),
                                 layout_.rgb_offset != 0 ? batch.rgb.data() : nullptr, max_color_seen_));
  next_point_ += *n;
  return *n;
}

StatusOr<size_t> LasReader::ReadBounds(Bounds& bounds, size_t max_points, PointBatch&) {
  ASSIGN_OR_RETURN(const size_t n, Fill(max_points));
  RETURN_IF_ERROR(layout_.Widen(buffer_.data(), n, next_point_, bounds, max_color_seen_));
  next_point_ += n;
  return n;
}

}  // namespace pointdag
