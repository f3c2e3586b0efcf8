// Binary little-endian PLY read by our own code, streamed from the file.
//
// PCL's PLY parser (pcl_reader.h) calls back per property and holds the whole cloud: for a Kinect
// scan it was half of an ingest. This reader takes the common layout only: the vertex element first,
// x, y and z as float or double, and colors as uchar red, green, blue or no property PCL would take
// for a color (rgb, rgba, r, g, b, alpha, diffuse_*). It gives exactly the points and colors PCL's
// reader gives for such a file; for any other layout OpenPlainPly returns null and the caller uses
// PCL. The header must have passed CheckPlyHeader (ply_pcd_header.h), which also checked that the
// body holds every record.
#pragma once

#include <filesystem>
#include <memory>

#include "pointdag/read/ply_pcd_header.h"
#include "pointdag/read/scan_reader.h"

namespace pointdag {

StatusOr<std::unique_ptr<ScanReader>> OpenPlainPly(const std::filesystem::path& path, const CheckedHeader& header);

}  // namespace pointdag
