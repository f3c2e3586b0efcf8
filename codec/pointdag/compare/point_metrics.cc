#include "pointdag/compare/point_metrics.h"

#include <flann/flann.hpp>

#include <cmath>

#include "pointdag/read/scan_reader.h"

namespace pointdag {
namespace {

// Nearest neighbour in `data` of every row of `queries` (both n x 3, row-major): index and squared distance.
void Nearest(std::vector<double>& data, std::vector<double>& queries, std::vector<uint32_t>& index, double& mse) {
  flann::Matrix<double> data_m(data.data(), data.size() / 3, 3);
  flann::Matrix<double> query_m(queries.data(), queries.size() / 3, 3);
  flann::Index<flann::L2_Simple<double>> tree(data_m, flann::KDTreeSingleIndexParams(12));
  tree.buildIndex();
  std::vector<size_t> idx(query_m.rows);
  std::vector<double> dist(query_m.rows);
  flann::Matrix<size_t> idx_m(idx.data(), idx.size(), 1);
  flann::Matrix<double> dist_m(dist.data(), dist.size(), 1);
  flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED);
  params.cores = 0;  // all cores
  tree.knnSearch(query_m, idx_m, dist_m, 1, params);
  index.assign(idx.begin(), idx.end());
  double sum = 0;
  for (double d : dist) sum += d;  // L2_Simple returns squared distances
  mse = sum / static_cast<double>(dist.size());
}

}  // namespace

StatusOr<OriginalCorrespondence> OriginalCorrespondence::Build(const std::filesystem::path& scan, const VoxelGrid& grid) {
  ASSIGN_OR_RETURN(std::unique_ptr<ScanReader> reader, OpenScan(scan));
  ASSIGN_OR_RETURN(const ScanSurvey survey, SurveyScan(*reader));
  OriginalCorrespondence out;
  std::vector<double> original;
  original.reserve(3 * survey.points);
  const double to_8bit = survey.color_bits > 8 ? 1.0 / 257.0 : 1.0;
  PointBatch batch;
  for (;;) {
    ASSIGN_OR_RETURN(size_t n, reader->Read(batch, 1 << 16));
    if (n == 0) break;
    for (size_t i = 0; i < n; ++i) {
      original.insert(original.end(), batch.xyz[i].begin(), batch.xyz[i].end());
      if (survey.has_color && grid.has_color()) {
        const auto ch = [&](int c) { return static_cast<uint8_t>(std::clamp(std::round(batch.rgb[i][c] * to_8bit), 0.0, 255.0)); };
        out.original_colors_.push_back({ch(0), ch(1), ch(2)});
      }
    }
  }
  std::vector<double> voxels;
  voxels.reserve(3 * grid.morton.size());
  for (uint64_t code : grid.morton) {
    const auto c = grid.VoxelCentre(code);
    voxels.insert(voxels.end(), c.begin(), c.end());
  }
  Nearest(voxels, original, out.nearest_voxel_, out.mse_original_to_voxels_);
  Nearest(original, voxels, out.nearest_original_, out.mse_voxels_to_original_);
  out.peak_ = grid.voxel_size * std::ldexp(1.0, grid.depth);
  return out;
}

double OriginalCorrespondence::d1_psnr() const {
  const double mse = d1_mse();
  return mse > 0 ? 10.0 * std::log10(3.0 * peak_ * peak_ / mse) : std::numeric_limits<double>::infinity();
}

double OriginalCorrespondence::ColorPsnrY(std::span<const Rgb8> voxel_colors) const {
  if (original_colors_.empty() || voxel_colors.size() != nearest_original_.size()) return std::nan("");
  double forward = 0, backward = 0;
  for (size_t i = 0; i < original_colors_.size(); ++i) {
    const double d = LumaBt709(original_colors_[i]) - LumaBt709(voxel_colors[nearest_voxel_[i]]);
    forward += d * d;
  }
  for (size_t v = 0; v < voxel_colors.size(); ++v) {
    const double d = LumaBt709(voxel_colors[v]) - LumaBt709(original_colors_[nearest_original_[v]]);
    backward += d * d;
  }
  forward /= static_cast<double>(original_colors_.size());
  backward /= static_cast<double>(voxel_colors.size());
  return PsnrFromMse(std::max(forward, backward));
}

}  // namespace pointdag
