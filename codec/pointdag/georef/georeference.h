// Stage 2 of the pipeline: source CRS -> WGS84 -> local ENU metres about the dataset's centre.
//
// Contract: the source CRS comes from, in order, the caller's EPSG override, the LAS WKT VLR, or an
// EPSG code in the GeoKeys; PROJ resolves it and transforms to WGS84 geographic (lat, lon,
// ellipsoidal h); GeographicLib's LocalCartesian gives east-north-up metres about the origin, the
// centre of the scan's bounds. Heights of a CRS without a vertical axis are taken in the CRS's
// linear unit (LAS convention: Z in the same unit as X and Y) and treated as ellipsoidal — without
// geoid grids there is nothing better, and the frame says so. A scan without any CRS stays in its
// own frame, in its own units, and the frame says that too. Coordinates that cannot lie in the
// stated CRS (a geocentric CRS whose points are nowhere near the Earth's surface, projected
// coordinates PROJ cannot invert) are kInvalidArgument with the reason, never silently wrong.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include <nlohmann/json.hpp>

#include "pointdag/read/scan_reader.h"

namespace pointdag {

struct GeoFrame {
  bool georeferenced = false;  // false: the scan's own frame, units unknown
  std::string crs_source;      // "epsg-override", "las-wkt", "las-geokeys" or "none"
  std::string crs_name;        // PROJ's name of the source CRS
  std::string crs_wkt;         // PROJ's WKT2 of the source CRS
  std::optional<int> epsg;     // when the CRS has an EPSG identifier
  double vertical_unit_m = 1;  // metres per source Z unit
  std::string vertical;        // how heights were treated
  std::array<double, 3> origin_llh{0, 0, 0};  // lat, lon (degrees), ellipsoidal h (m)
  std::array<double, 16> enu_to_ecef{};       // column-major 4x4, as 3D Tiles and Cesium use
  // Set when ToEnu maps the scan's bounds through a fitted polynomial (local_enu_map.h): its worst
  // error against the exact transform, metres.
  std::optional<double> enu_fit_error_m;
};

// The CRS definition PROJ should use for a scan, or nullopt when it has none.
std::optional<std::pair<std::string, std::string>> SourceCrsOf(const ScanInfo& scan, std::optional<int> epsg_override);

class Georeferencer {
 public:
  // `crs` is anything PROJ accepts ("EPSG:2994", WKT); `centre` a point of the scan in source units.
  static StatusOr<std::unique_ptr<Georeferencer>> Create(const std::string& crs, const std::string& crs_source,
                                                         const std::array<double, 3>& centre);
  ~Georeferencer();
  Georeferencer(const Georeferencer&) = delete;
  Georeferencer& operator=(const Georeferencer&) = delete;

  const GeoFrame& frame() const { return frame_; }
  // Source coordinates -> WGS84 (lat, lon, h), in place.
  Status ToGeographic(std::span<std::array<double, 3>> points) const;
  // Source coordinates -> ENU metres about the origin, in place.
  Status ToEnu(std::span<std::array<double, 3>> points) const;
  // From now on ToEnu maps points inside `bounds` through a fitted polynomial when one is within
  // kLocalEnuTolerance_m of the exact transform everywhere in them (else it stays exact);
  // frame().enu_fit_error_m says which. Not thread-safe against concurrent ToEnu.
  void FitLocalEnu(const Bounds& bounds);
  static constexpr double kLocalEnuTolerance_m = 5e-5;

 private:
  struct Impl;
  explicit Georeferencer(std::unique_ptr<Impl> impl);
  Status Transform(std::span<std::array<double, 3>> points, bool to_enu) const;
  bool TransformExactly(std::span<std::array<double, 3>> part, bool to_enu) const;  // false: a point failed
  std::unique_ptr<Impl> impl_;
  GeoFrame frame_;
};

// A reader whose points come out in ENU metres (Voxelize() reads through it unchanged).
class EnuReader : public ScanReader {
 public:
  EnuReader(std::unique_ptr<ScanReader> source, std::unique_ptr<Georeferencer> georeferencer);
  StatusOr<size_t> Read(PointBatch& batch, size_t max_points) override;
  Status Rewind() override { return source_->Rewind(); }
  const Georeferencer& georeferencer() const { return *georeferencer_; }

 private:
  std::unique_ptr<ScanReader> source_;
  std::unique_ptr<Georeferencer> georeferencer_;
};

// The frame as dataset metadata: CRS, ENU origin, ENU->ECEF matrix (column-major).
nlohmann::json DescribeFrame(const GeoFrame& frame);

struct FramedReader {
  std::unique_ptr<ScanReader> reader;  // an EnuReader when georeferenced, else the scan's own reader
  GeoFrame frame;
};

// Opens a scan to be read in ENU metres when it has a CRS (or `epsg` names one), else in its own
// frame. The origin is the centre of the header bounds when the first points lie inside them, else
// of a full survey pass.
StatusOr<FramedReader> OpenScanInFrame(const std::filesystem::path& path, std::optional<int> epsg);

}  // namespace pointdag
