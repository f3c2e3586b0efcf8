#include "pointdag/compare/scorecard.h"

#include <cmath>

#include "pointdag/compare/draco_compare.h"
#include "pointdag/compare/point_metrics.h"

namespace pointdag {

StatusOr<nlohmann::json> BuildScorecard(const EncodedScan& scan, std::span<const double> targets) {
  ASSIGN_OR_RETURN(const std::vector<uint8_t> zstd_stream, EncodeDag(scan.dag, GeometryCoder::kZstd));
  ASSIGN_OR_RETURN(const DracoResult draco, DracoEncodeVoxels(scan.grid));
  const double voxels = static_cast<double>(scan.grid.morton.size());
  const auto bpv = [&](size_t bytes) { return 8.0 * static_cast<double>(bytes) / voxels; };
  const double geometry = bpv(std::min(scan.file.geometry.size(), zstd_stream.size()));
  const auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };

  // The whole pipeline against the original points: voxelization's geometric error, and below, each
  // codec's colors as seen from the original points.
  ASSIGN_OR_RETURN(const OriginalCorrespondence original, OriginalCorrespondence::Build(scan.source, scan.grid));

  nlohmann::json codecs = nlohmann::json::array();
  if (scan.grid.has_color()) {
    std::vector<ColorEncodeOptions> trials;
    for (ColorCodec codec : {ColorCodec::kVariableRate, ColorCodec::kFixedRate, ColorCodec::kHierarchical}) {
      for (double target : targets) trials.push_back({codec, target});
    }
    // The 2D mapping (Paper IIA) along both curves.
    for (Curve curve : {Curve::kHilbert, Curve::kMorton}) {
      for (ColorCodec codec : {ColorCodec::kJpeg, ColorCodec::kWebp, ColorCodec::kAstc}) {
        for (double target : targets) trials.push_back({codec, target, 16.0, curve});
      }
      trials.push_back({ColorCodec::kPng, std::nullopt, 16.0, curve});
    }
    trials.push_back({ColorCodec::kLossless, std::nullopt});
    trials.push_back({ColorCodec::kRaw, std::nullopt});
    for (const ColorEncodeOptions& trial : trials) {
      auto encoded = EncodeColors(scan.grid.colors, trial, scan.grid.morton);
      if (!encoded.ok() && encoded.status().code() == StatusCode::kInvalidArgument) continue;  // target out of its reach
      if (!encoded.ok()) return encoded.status();
      const EncodedColors& colors = *encoded;
      ASSIGN_OR_RETURN(const std::vector<Rgb8> decoded, DecodeColors(colors.bytes, scan.grid.colors.size(), scan.grid.morton));
      const double color_bits = bpv(colors.bytes.size());
      const bool image = trial.codec == ColorCodec::kPng || trial.codec == ColorCodec::kJpeg ||
                         trial.codec == ColorCodec::kWebp || trial.codec == ColorCodec::kAstc;
      codecs.push_back({{"name", ColorCodecName(trial.codec)},
                        {"curve", image ? nlohmann::json(CurveName(trial.curve)) : nlohmann::json()},
                        {"target_psnr", trial.target_psnr_y ? nlohmann::json(*trial.target_psnr_y) : nlohmann::json()},
                        {"psnr_y", finite_or_null(colors.psnr.y)},
                        {"psnr_rgb", finite_or_null(colors.psnr.rgb)},
                        {"lossless", !std::isfinite(colors.psnr.y)},
                        {"psnr_y_vs_original", finite_or_null(original.ColorPsnrY(decoded))},
                        {"blocks", colors.blocks},
                        {"color_bits_per_voxel", color_bits},
                        {"total_bits_per_voxel", geometry + color_bits},
                        {"draco_over_ours", draco.bits_per_point / (geometry + color_bits)}});
    }
  }
  return nlohmann::json{
      {"points", scan.grid.points_in},
      {"voxels", scan.grid.morton.size()},
      {"depth", scan.grid.depth},
      {"voxel_size", scan.grid.voxel_size},
      {"geometry_bits_per_voxel", geometry},
      {"geometry", {{"resident_bits_per_voxel", bpv(scan.dag.ResidentBytes())},
                    {"stored_context_bits_per_voxel", bpv(scan.file.geometry.size())},
                    {"stored_zstd_bits_per_voxel", bpv(zstd_stream.size())},
                    {"unique_nodes", scan.dag.UniqueNodeCount()}}},
      {"original", {{"d1_mse", original.d1_mse()},
                    {"d1_psnr", finite_or_null(original.d1_psnr())},
                    {"psnr_y_voxel_colors", finite_or_null(original.ColorPsnrY(scan.grid.colors))}}},
      {"draco_bits_per_point", draco.bits_per_point},
      {"draco", {{"bytes", draco.bytes}, {"method", draco.method}, {"speed", draco.speed}, {"level10_encode_s", draco.level10_seconds},
                 {"decode_s", draco.decode_seconds}}},
      {"codecs", codecs},
  };
}

}  // namespace pointdag
