// The scorecard of one scan: geometry bits, every color codec at 30/34/38/42 dB PSNR-Y and
// lossless, and Draco on the same voxels. `pointdag compare` prints it; `pointdag bench --colors`
// tabulates it over a folder of scans.
#pragma once

#include <filesystem>

#include <nlohmann/json.hpp>

#include "pointdag/pipeline.h"

namespace pointdag {

// JSON: {"voxels", "points", "depth", "voxel_size", "geometry_bits_per_voxel", "geometry": {...},
//        "draco_bits_per_point", "draco": {...}, "codecs": [{"name", "target_psnr", "psnr_y",
//        "psnr_rgb", "lossless", "color_bits_per_voxel", "total_bits_per_voxel", "draco_over_ours"}]}
StatusOr<nlohmann::json> BuildScorecard(const EncodedScan& scan);

}  // namespace pointdag
