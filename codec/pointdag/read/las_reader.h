// LAS 1.0-1.4 reader, point data record formats 0-10, streaming.
//
// Debian ships no LAS library, so this is our own parser of the ASPRS LAS 1.4 R15 layout. It keeps
// the WKT (VLR/EVLR 2112) and the GeoTIFF keys (34735-34737) as metadata, skips extra bytes by
// honouring the header's record length, and prefers the 64-bit point count of LAS 1.4.
// Every count and offset is checked against the file size before anything is allocated.
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>

#include "pointdag/read/scan_reader.h"

namespace pointdag {

class LasReader final : public ScanReader {
 public:
  static StatusOr<std::unique_ptr<ScanReader>> Open(const std::filesystem::path& path);
  ~LasReader() override;

  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override;
  Status Rewind() override;

 private:
  LasReader() = default;
  Status ParseHeader(uint64_t file_size);

  std::FILE* file_ = nullptr;
  std::string path_;
  uint64_t point_data_offset_ = 0;
  uint32_t record_length_ = 0;
  uint32_t rgb_offset_ = 0;  // byte offset of RGB inside a record, 0 when absent
  std::array<double, 3> scale_{1, 1, 1};
  std::array<double, 3> offset_{0, 0, 0};
  uint64_t next_point_ = 0;
  std::vector<unsigned char> buffer_;
};

}  // namespace pointdag
