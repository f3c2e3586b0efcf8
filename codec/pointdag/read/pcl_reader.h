// PLY (ascii, binary little/big endian) and PCD readers, through PCL's pcl_io.
//
// PCL's io library loads 67 more shared libraries (VTK, Qt, OpenNI, MPI, ...), which cost every
// process start of the CLI and the daemon about 5 ms of dynamic loading and lazy symbol lookups,
// while only the PLY layouts our own reader does not take (ply_reader.h) and PCD need them. So
// pcl_reader.cc is built as a module, libpointdag_pcl_reader.so, that OpenPclScan loads on first
// use (pcl_loader.cc): from $POINTDAG_PCL_READER, the build tree, or lib/pointdag/ beside the
// executable's bin/. PCL's headers stay inside pcl_reader.cc. Coordinates may be float or double;
// colors may be packed rgb/rgba, or separate red/green/blue (or r/g/b) channels of any numeric type.
// Float channels in [0,1] are scaled to 0-255. The whole cloud is held in PCL's buffer (neither
// format has a streaming reader in PCL); batches are converted from it on demand.
#pragma once

#include <filesystem>
#include <memory>

#include "pointdag/read/scan_reader.h"

namespace pointdag {

// kUnsupported, naming where it looked, when the module cannot be loaded.
StatusOr<std::unique_ptr<ScanReader>> OpenPclScan(const std::filesystem::path& path, ScanFormat format);

// The module's entry point (C linkage, looked up by name): OpenPclScan's result through a pointer.
using OpenPclScanFn = void (*)(const char* path, ScanFormat format, StatusOr<std::unique_ptr<ScanReader>>* out);
inline constexpr const char* kOpenPclScanSymbol = "pointdag_open_pcl_scan";

}  // namespace pointdag
