// LAS 1.0-1.4 reader, point data record formats 0-10, streaming.
//
// Debian ships no LAS library, so this is our own parser of the ASPRS LAS 1.4 R15 layout
// (las_header.h). It skips extra bytes by honouring the header's record length and prefers the
// 64-bit point count of LAS 1.4. The point count is checked against the data before reading.
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>

#include "pointdag/read/las_header.h"
#include "pointdag/read/scan_reader.h"

namespace pointdag {

class LasReader final : public ScanReader {
 public:
  // Opens a LAS or LAZ file: a LAZ header (the compression bit) hands over to LazReader.
  static StatusOr<std::unique_ptr<ScanReader>> Open(const std::filesystem::path& path);
  ~LasReader() override;

  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override;
  Status Rewind() override;
  StatusOr<size_t> ReadBounds(Bounds& bounds, size_t max_points, PointBatch& scratch) override;

 private:
  LasReader() = default;
  // The next up to max_points records into buffer_; how many.
  StatusOr<size_t> Fill(size_t max_points);

  std::FILE* file_ = nullptr;
  std::string path_;
  LasHeader header_;
  LasRecordLayout layout_;
  uint64_t next_point_ = 0;
  std::vector<unsigned char> buffer_;
};

}  // namespace pointdag
