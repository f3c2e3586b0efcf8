// Our own check of PLY and PCD headers, run before PCL's parsers see a byte of the file.
//
// PCL trusts what a header declares: it allocates points × record size before reading a body, takes
// counts that are not numbers for numbers, and crashes on headers with no fields. So no PLY or PCD
// reaches PCL unless CheckPlyHeader / CheckPcdHeader accepted it first.
//
// Contract. Each reads at most the first kMaxHeaderBytes of the file (plus, for a binary_compressed
// PCD, the two size words after the header), parses the whole header by its format's specification,
// and returns the point count and encoding only if
//   - the header is well formed: known keywords only (PLY: format, element, property [list],
//     comment, obj_info, end_header; PCD: VERSION FIELDS SIZE TYPE COUNT WIDTH HEIGHT VIEWPOINT
//     POINTS DATA, in that order, COUNT / VERSION / VIEWPOINT optional), integers that are plain
//     decimal integers, per-field lists as long as FIELDS, sizes that fit their types, no control
//     bytes, no line longer than kMaxLineBytes, the end of the header within kMaxHeaderBytes,
//     WIDTH × HEIGHT == POINTS, and x, y and z present                         -> kMalformed
//   - it uses only layouts the reader handles (no list property in a PLY vertex, no range_grid, no
//     PCD TYPE other than I, U, F)                                             -> kUnsupported
//   - no declared count is absurd: points, fields, per-field COUNT, record size (kMax* below)
//                                                                              -> kResourceLimit
//   - every count fits in the bytes after the header: a binary record of B bytes needs B bytes, an
//     ASCII value at least 2 (one character and a separator); a binary_compressed payload's size
//     words must agree with the header, fit in the file, and not claim more than LZF can expand the
//     compressed bytes to                                                      -> kTruncated / kMalformed
// A PCD body whose first line PCL would read as one more header line is refused too (PCL keeps
// parsing header keywords after DATA), so PCL allocates no more than the checked header allows.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pointdag/status.h"

namespace pointdag {

inline constexpr size_t kMaxHeaderBytes = 1 << 20;
inline constexpr size_t kMaxLineBytes = 16 << 10;
inline constexpr uint64_t kMaxPoints = 0xFFFFFFFFu;   // PCL counts points in 32 bits
inline constexpr size_t kMaxFields = 1024;            // PLY properties per element, PCD fields
inline constexpr uint64_t kMaxFieldCount = 1 << 16;   // PCD COUNT of one field
inline constexpr uint64_t kMaxRecordBytes = 1 << 20;  // one point's bytes
inline constexpr size_t kMaxPlyElements = 256;

struct PlyScalar {
  std::string name;
  std::string type;  // as written: uchar or uint8, float or float32, ...
};

struct CheckedHeader {
  uint64_t points = 0;
  std::string encoding;  // PLY: ascii, binary_little_endian, binary_big_endian; PCD: ascii, binary, binary_compressed
  // PLY: where the body starts, and the vertex element's properties (all scalars) in record order
  // when it is the first element (else empty): what a reader of its own needs (ply_reader.h).
  uint64_t body_offset = 0;
  std::vector<PlyScalar> first_vertex_scalars;
};

StatusOr<CheckedHeader> CheckPlyHeader(const std::filesystem::path& path);
StatusOr<CheckedHeader> CheckPcdHeader(const std::filesystem::path& path);

}  // namespace pointdag
