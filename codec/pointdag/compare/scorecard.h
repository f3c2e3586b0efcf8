// The scorecard of one scan: geometry bits, every color codec at 30/34/38/42 dB PSNR-Y and
// lossless, and Draco on the same voxels. `pointdag compare` prints it; `pointdag bench --colors`
// tabulates it over a folder of scans; the nightly benchmark (bench/) reports it per corpus case.
#pragma once

#include <filesystem>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "pointdag/pipeline.h"

namespace pointdag {

// JSON: {"voxels", "points", "depth", "voxel_size", "geometry_bits_per_voxel", "geometry": {...},
//        "original": {"d1_mse", "d1_psnr", "psnr_y_voxel_colors"}, "draco_bits_per_point",
//        "draco": {"bytes", "method", "speed", "level10_encode_s", "decode_s"}, "codecs": [{"name", "curve", "target_psnr", "psnr_y" (over voxels),
//        "psnr_y_vs_original" (pc_error style, against the original points), "psnr_rgb", "lossless",
//        "color_bits_per_voxel", "total_bits_per_voxel", "draco_over_ours"}]}
// Draco codes the same voxels losslessly, so its quality against the originals is the voxels' own
// ("original.psnr_y_voxel_colors").
// `targets`: the PSNR-Y targets of the lossy codecs (`pointdag compare`: 30, 34, 38 and 42 dB).
inline const std::vector<double> kScorecardTargets = {30.0, 34.0, 38.0, 42.0};
StatusOr<nlohmann::json> BuildScorecard(const EncodedScan& scan, std::span<const double> targets = kScorecardTargets);

}  // namespace pointdag
