#include "pointdag/read/scan_reader.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <limits>

#include "pointdag/read/las_reader.h"
#include "pointdag/read/pcl_reader.h"
#include "pointdag/read/ply_reader.h"

namespace pointdag {

StatusOr<std::unique_ptr<ScanReader>> OpenScan(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return IoError("cannot open " + path.string());
  char magic[16] = {};
  const size_t got = std::fread(magic, 1, sizeof(magic), f);
  std::fclose(f);
  if (got >= 4 && std::memcmp(magic, "LASF", 4) == 0) return LasReader::Open(path);  // LAZ too: LasReader hands it over
  if (got >= 4 && std::memcmp(magic, "ply", 3) == 0 && (magic[3] == '\n' || magic[3] == '\r')) {
    ASSIGN_OR_RETURN(const CheckedHeader header, CheckPlyHeader(path));
    ASSIGN_OR_RETURN(std::unique_ptr<ScanReader> plain, OpenPlainPly(path, header));
    return plain ? std::move(plain) : OpenPclScan(path, ScanFormat::kPly);
  }
  // PCD files open with a comment line or directly with VERSION/FIELDS.
  if (got >= 5 && (std::memcmp(magic, "# .PCD", 6) == 0 || std::memcmp(magic, "VERSION", 7) == 0 ||
                   std::memcmp(magic, "FIELDS", 6) == 0)) {
    return OpenPclScan(path, ScanFormat::kPcd);
  }
  if (got == 0) return Malformed(path.string() + " is empty");
  return Unsupported(path.string() + " is not a LAS, LAZ, PLY or PCD scan (unrecognised first bytes)");
}

StatusOr<ScanSurvey> SurveyScan(ScanReader& reader, size_t batch_points) {
  ScanSurvey survey;
  constexpr double inf = std::numeric_limits<double>::infinity();
  survey.bounds.min = {inf, inf, inf};
  survey.bounds.max = {-inf, -inf, -inf};
  RETURN_IF_ERROR(reader.Rewind());
  PointBatch batch;
  for (;;) {
    ASSIGN_OR_RETURN(size_t n, reader.ReadBounds(survey.bounds, batch_points, batch));
    if (n == 0) break;
    survey.points += n;
  }
  if (survey.points == 0) return Malformed("the scan holds zero points");
  survey.has_color = reader.info().has_color;
  survey.color_bits = reader.max_color_seen() <= 255 ? 8 : reader.info().stored_color_bits;
  RETURN_IF_ERROR(reader.Rewind());
  return survey;
}

}  // namespace pointdag
