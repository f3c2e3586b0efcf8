// The LAS file header shared by LAS and LAZ: the public header block, the VLRs and EVLRs, and the
// layout of a point record. LasReader reads the records as stored; LazReader decompresses them
// first (the same header with the point format's compression bit set).
//
// Contract: ReadLasHeader() checks every field against the file's real size before allocating;
// it keeps the CRS (WKT 2112, GeoKeys 34735-34737) in `info` and the payloads of the few records
// the readers need (the LASzip VLR, the COPC info VLR). It does not check the point count against
// the data, which only the reader of the records can (LAZ data is smaller than n * record length).
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "pointdag/read/scan_reader.h"

namespace pointdag {

struct LasHeader {
  int version_minor = 0;
  uint16_t header_size = 0;
  uint64_t point_data_offset = 0;
  uint64_t point_data_end = 0;  // the EVLRs' start, or the end of the file
  uint64_t file_size = 0;
  int point_format = 0;         // 0-10, the compression bits cleared
  bool compressed = false;      // LAZ: bit 7 (or 6) of the point format byte
  uint32_t record_length = 0;
  uint64_t point_count = 0;     // the 64-bit count of LAS 1.4 when set, else the legacy one
  std::optional<std::vector<unsigned char>> laszip_vlr;  // user "laszip encoded", record 22204
  std::optional<std::vector<unsigned char>> copc_info;   // user "copc", record 1
};

// How the reader turns a record into a point: the scale/offset of the integer coordinates and
// where the 16-bit RGB channels are.
struct LasRecordLayout {
  uint32_t record_length = 0;
  uint32_t rgb_offset = 0;  // 0 when the point format has no color
  std::array<double, 3> scale{1, 1, 1};
  std::array<double, 3> offset{0, 0, 0};

  // Appends n records to `batch` (coordinates, and colors when rgb_offset != 0); `first_index` is
  // the first record's number in the file, for the message about a non-finite coordinate.
  Status Append(const unsigned char* records, size_t n, uint64_t first_index, PointBatch& batch,
                uint16_t& max_color_seen) const;
  // The same into n points at xyz (and rgb unless null); a non-finite point may leave the rest unset.
  Status Decode(const unsigned char* records, size_t n, uint64_t first_index, std::array<double, 3>* xyz,
                std::array<uint16_t, 3>* rgb, uint16_t& max_color_seen) const;
  // Widens `bounds` by n records as Decode's points would (and max_color_seen), with its errors.
  // x * scale + offset is monotonic in the stored integer x (scale and offset are finite, scale is
  // not zero, and rounding is monotonic): the extremes are those of the two extreme integers.
  Status Widen(const unsigned char* records, size_t n, uint64_t first_index, Bounds& bounds,
               uint16_t& max_color_seen) const;
};

// Reads and checks the header of an open LAS/LAZ file of `file_size` bytes; fills `info`.
StatusOr<LasHeader> ReadLasHeader(std::FILE* file, uint64_t file_size, ScanInfo& info, LasRecordLayout& layout);

// Reads n bytes at an absolute offset; a short read is Truncated naming `what`.
Status ReadAt(std::FILE* file, uint64_t offset, void* out, size_t n, const char* what);

}  // namespace pointdag
