// Stage 1 of the pipeline: read a scan from disk in batches.
//
// Contract: OpenScan() recognises the format from the file's first bytes (not its name), validates
// every header field against the file's real size before allocating anything, and returns a reader
// that streams points in batches. Readers never invent data: a scan without color reports
// has_color == false. Colors are passed through as stored (LAS: 16-bit fields) together with the
// largest value seen, so the voxelizer can tell 8-bit values kept in 16-bit fields from true
// 16-bit color. A point with a NaN or infinite coordinate is an error, not a silent skip.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pointdag/read/laz/copc_info.h"
#include "pointdag/status.h"

namespace pointdag {

enum class ScanFormat { kLas, kPly, kPcd };  // LAZ and COPC are kLas with `compression` set
constexpr const char* ScanFormatName(ScanFormat format) {
  switch (format) {
    case ScanFormat::kLas: return "LAS";
    case ScanFormat::kPly: return "PLY";
    case ScanFormat::kPcd: return "PCD";
  }
  return "?";
}

struct Bounds {
  std::array<double, 3> min{0, 0, 0};
  std::array<double, 3> max{0, 0, 0};
};

// One GeoTIFF key as stored in a LAS GeoKeyDirectory (record 34735).
struct GeoKey {
  uint16_t id = 0;
  uint16_t location = 0;  // 0: value inline; 34736: index into doubles; 34737: offset into ascii
  uint16_t count = 0;
  uint16_t value = 0;
};

struct GeoKeys {
  std::vector<GeoKey> keys;
  std::vector<double> doubles;  // record 34736
  std::string ascii;            // record 34737
};

struct ScanInfo {
  ScanFormat format = ScanFormat::kLas;
  std::string format_version;   // "1.2", "1.4", "ascii", "binary_little_endian", ...
  int las_point_format = -1;    // LAS only
  uint64_t point_count = 0;     // as declared (and validated against the file size)
  std::optional<Bounds> header_bounds;  // LAS header bounds; may be stale, never trusted for voxelizing
  bool has_color = false;
  int stored_color_bits = 8;    // width of the stored color fields: 16 for LAS, 8 for PLY/PCD
  std::string crs_wkt;          // LAS WKT VLR/EVLR (2112), empty if none
  std::optional<GeoKeys> geokeys;
  // LAZ: how the records were compressed ("LASzip 3.4r3 layered, 65 variable chunks: POINT14:30:v3
  // RGB14:6:v3"); empty for a plain LAS file.
  std::string compression;
  std::optional<laz::CopcHierarchy> copc;  // a COPC file's octree index (its `problem` says if unusable)
};

// Points of one batch, structure-of-arrays so consumers touch only what they need.
struct PointBatch {
  std::vector<std::array<double, 3>> xyz;
  std::vector<std::array<uint16_t, 3>> rgb;  // empty when the scan has no color
  size_t size() const { return xyz.size(); }
  void clear() { xyz.clear(); rgb.clear(); }
};

class ScanReader {
 public:
  virtual ~ScanReader() = default;
  const ScanInfo& info() const { return info_; }
  // Largest color channel value among the points read so far (0 without color).
  uint16_t max_color_seen() const { return max_color_seen_; }

  // Replaces `batch` with up to `max_points` next points. Returns how many; 0 once at the end.
  virtual StatusOr<size_t> Read(PointBatch& batch, size_t max_points) = 0;
  // Starts over from the first point (readers are read twice: once for bounds, once to voxelize).
  virtual Status Rewind() = 0;
  // The survey pass's read: up to max_points next points widen `bounds` (and max_color_seen) as
  // Read's points would, with Read's errors. This default reads them into `scratch`; readers that
  // can take the extremes from their stored values, without making points, override it. (Inline:
  // ScanReader has no out-of-line virtual, so the PCL reader's library needs no scan_reader.cc.)
  virtual StatusOr<size_t> ReadBounds(Bounds& bounds, size_t max_points, PointBatch& scratch) {
    ASSIGN_OR_RETURN(const size_t n, Read(scratch, max_points));
    for (const auto& p : scratch.xyz) {
      for (int axis = 0; axis < 3; ++axis) {
        bounds.min[axis] = std::min(bounds.min[axis], p[axis]);
        bounds.max[axis] = std::max(bounds.max[axis], p[axis]);
      }
    }
    return n;
  }

 protected:
  ScanInfo info_;
  uint16_t max_color_seen_ = 0;
};

// Opens any supported scan: LAS, LAZ (COPC too), PLY, PCD.
StatusOr<std::unique_ptr<ScanReader>> OpenScan(const std::filesystem::path& path);

// Summary of a full pass over the scan: exact bounds, counts and color depth.
struct ScanSurvey {
  Bounds bounds;
  uint64_t points = 0;
  bool has_color = false;
  int color_bits = 8;  // 8 when all stored values fit in 8 bits, else the stored width
};

// Reads the whole scan once (bounded memory), then rewinds it.
StatusOr<ScanSurvey> SurveyScan(ScanReader& reader, size_t batch_points = 1 << 16);

}  // namespace pointdag
