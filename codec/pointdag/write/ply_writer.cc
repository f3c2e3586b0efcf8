#include "pointdag/write/ply_writer.h"

#include "pointdag/container/pdag_file.h"
#include "pointdag/read/byte_io.h"

namespace pointdag {

Status WriteVoxelsPly(const std::filesystem::path& path, const VoxelGrid& grid, const std::optional<PlyScalar>& scalar) {
  if (scalar && scalar->values.size() != grid.morton.size()) {
    return InvalidArgument("PLY property " + scalar->name + " has " + std::to_string(scalar->values.size()) +
                           " values for " + std::to_string(grid.morton.size()) + " voxels");
  }
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by pointdag\nelement vertex " +
                       std::to_string(grid.morton.size()) + "\nproperty double x\nproperty double y\nproperty double z\n";
  if (grid.has_color()) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (scalar) header += "property float " + scalar->name + "\n";
  header += "end_header\n";
  std::vector<uint8_t> out(header.begin(), header.end());
  out.reserve(out.size() + grid.morton.size() * 31);
  for (size_t i = 0; i < grid.morton.size(); ++i) {
    for (double v : grid.VoxelCentre(grid.morton[i])) AppendLE<double>(out, v);
    if (grid.has_color()) {
      out.push_back(grid.colors[i].r);
      out.push_back(grid.colors[i].g);
      out.push_back(grid.colors[i].b);
    }
    if (scalar) AppendLE<float>(out, scalar->values[i]);
  }
  return WriteFileAtomically(path, out);
}

}  // namespace pointdag
