// PLY (ascii, binary little/big endian) and PCD readers, through PCL's pcl_io.
//
// PCL's headers are heavy, so they stay inside pcl_reader.cc. Coordinates may be float or double;
// colors may be packed rgb/rgba, or separate red/green/blue (or r/g/b) channels of any numeric type.
// Float channels in [0,1] are scaled to 0-255. The whole cloud is held in PCL's buffer (neither
// format has a streaming reader in PCL); batches are converted from it on demand.
#pragma once

#include <filesystem>
#include <memory>

#include "pointdag/read/scan_reader.h"

namespace pointdag {

StatusOr<std::unique_ptr<ScanReader>> OpenPclScan(const std::filesystem::path& path, ScanFormat format);

}  // namespace pointdag
