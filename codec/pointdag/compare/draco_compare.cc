#include "pointdag/compare/draco_compare.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/point_cloud/point_cloud_builder.h>

#include <chrono>

#include "pointdag/voxelize/morton.h"

namespace pointdag {

StatusOr<DracoResult> DracoEncodeVoxels(const VoxelGrid& grid, DracoSearch search) {
  const size_t n = grid.morton.size();
  if (n == 0) return InvalidArgument("no voxels to encode");
  std::vector<uint32_t> cells(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const auto c = MortonDecode(grid.morton[i]);
    std::copy(c.begin(), c.end(), cells.begin() + 3 * i);
  }
  draco::PointCloudBuilder builder;
  builder.Start(static_cast<draco::PointIndex::ValueType>(n));
  const int pos = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_UINT32);
  builder.SetAttributeValuesForAllPoints(pos, cells.data(), 3 * sizeof(uint32_t));
  if (grid.has_color()) {
    const int color = builder.AddAttribute(draco::GeometryAttribute::COLOR, 3, draco::DT_UINT8);
    builder.SetAttributeValuesForAllPoints(color, grid.colors.data(), sizeof(Rgb8));
  }
  std::unique_ptr<draco::PointCloud> cloud = builder.Finalize(false);
  if (!cloud) return Internal("Draco refused the point cloud");

  DracoResult best;
  draco::EncoderBuffer best_buffer;
  const std::vector<int> methods = search == DracoSearch::kExhaustive
                                        ? std::vector<int>{draco::POINT_CLOUD_KD_TREE_ENCODING, draco::POINT_CLOUD_SEQUENTIAL_ENCODING}
                                        : std::vector<int>{draco::POINT_CLOUD_KD_TREE_ENCODING};
  const int slowest = search == DracoSearch::kExhaustive ? 10 : 0;
  for (int method : methods) {
    for (int speed = 0; speed <= slowest; ++speed) {
      draco::Encoder encoder;
      encoder.SetEncodingMethod(method);
      encoder.SetSpeedOptions(speed, speed);
      draco::EncoderBuffer buffer;
      const auto start = std::chrono::steady_clock::now();
      if (!encoder.EncodePointCloudToBuffer(*cloud, &buffer).ok()) continue;
      if (method == draco::POINT_CLOUD_KD_TREE_ENCODING && speed == 0) {
        best.level10_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      }
      if (best.bytes == 0 || buffer.size() < best.bytes) {
        best.bytes = buffer.size();
        best.method = method == draco::POINT_CLOUD_KD_TREE_ENCODING ? "kd-tree" : "sequential";
        best.speed = speed;
        best_buffer.Clear();
        best_buffer.Encode(buffer.data(), buffer.size());
      }
    }
  }
  if (best.bytes == 0) return Internal("Draco could not encode the voxels with any method");

  best.bits_per_point = 8.0 * static_cast<double>(best.bytes) / static_cast<double>(n);
  // The daemon (kBestLevel) stores only the size: it does not decode (a fifth of Draco's time there).
  if (search == DracoSearch::kBestLevel) return best;
  for (int pass = 0; pass < 3; ++pass) {
    draco::DecoderBuffer in;
    in.Init(best_buffer.data(), best_buffer.size());
    draco::Decoder decoder;
    const auto start = std::chrono::steady_clock::now();
    auto decoded = decoder.DecodePointCloudFromBuffer(&in);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!decoded.ok() || decoded.value()->num_points() != n) {
      return Internal("Draco's smallest encoding does not decode back to the same number of points");
    }
    if (pass == 0 || seconds < best.decode_seconds) best.decode_seconds = seconds;
  }
  return best;
}

}  // namespace pointdag
