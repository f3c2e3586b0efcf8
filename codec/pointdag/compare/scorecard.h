// The scorecard of one scan: geometry bits, every color codec at 30/34/38/42 dB PSNR-Y and
// lossless, and Draco on the same voxels. `pointdag compare` prints it; `pointdag bench --colors`
// tabulates it over a folder of scans.
#pragma once

#include <filesystem>

#include <nlohmann/json.hpp>

#include "pointdag/pipeline.h"

namespace pointdag {

// JSON: {"voxels", "points", "depth", "voxel_size", "geometry_bits_per_voxel", "geometry": {...},
//        "original": {"d1_mse", "d1_psnr", "psnr_y_voxel_colors"}, "draco_bits_per_point",
//        "draco": {...}, "codecs": [{"name", "curve", "target_psnr", "psnr_y" (over voxels),
//        "psnr_y_vs_original" (pc_error style, against the original points), "psnr_rgb", "lossless",
//        "color_bits_per_voxel", "total_bits_per_voxel", "draco_over_ours"}]}
// Draco codes the same voxels losslessly, so its quality against the originals is the voxels' own
// ("original.psnr_y_voxel_colors").
StatusOr<nlohmann::json> BuildScorecard(const EncodedScan& scan);

}  // namespace pointdag
