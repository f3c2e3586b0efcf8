// DecodePdag (declared in pipeline.h): .pdag -> voxels and colors, apart from the encoding stages
// so that a decoder-only build (the WebAssembly one, web/wasm) compiles without their libraries.
#include <limits>

#include "pointdag/color/mip_colors.h"
#include "pointdag/container/json_fields.h"
#include "pointdag/pipeline.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {

StatusOr<DecodedPdag> DecodePdag(const PdagFile& file, const DecodeLimits& limits) {
  // Nothing the metadata declares is allocated by: the voxel count only bounds the geometry
  // decoder, and must then equal what the geometry really holds before anything is enumerated.
  const JsonFields meta(file.meta, ".pdag metadata");
  DecodedPdag out;
  ASSIGN_OR_RETURN(const uint64_t voxels, meta.Uint("voxels", std::numeric_limits<uint64_t>::max()));
  if (voxels > limits.max_voxels) {
    return ResourceLimit(".pdag declares " + std::to_string(voxels) + " voxels, more than the " +
                         std::to_string(limits.max_voxels) + " this decoder allows");
  }
  ASSIGN_OR_RETURN(const int64_t depth, meta.Int("depth", 2, kMaxDepth));
  out.grid.depth = static_cast<int>(depth);
  ASSIGN_OR_RETURN(out.grid.voxel_size, meta.Number("voxel_size"));
  ASSIGN_OR_RETURN(out.grid.origin, meta.Vec3("origin"));
  ASSIGN_OR_RETURN(out.grid.points_in, meta.UintOr("source/points", std::numeric_limits<uint64_t>::max(), 0));
  // Every unique node has a voxel below it on each level: that bounds the nodes of a true header.
  const uint64_t max_nodes = std::min(voxels * static_cast<uint64_t>(depth) + 64, limits.max_nodes);
  ASSIGN_OR_RETURN(out.dag, DecodeDag(file.geometry, max_nodes));
  if (out.dag.depth != out.grid.depth) return Corrupt(".pdag metadata depth disagrees with its geometry");
  // In leaf mode the root's count is the voxel count; in mipmap mode it counts every node, voxels
  // included, so it bounds what enumerating the voxels and decoding the colors can produce.
  const uint64_t root_count = out.dag.RootCount();
  if ((out.dag.mode == CountMode::kLeaves && root_count != voxels) || root_count < voxels) {
    return Corrupt(".pdag metadata voxel count disagrees with its geometry");
  }
  if (root_count > limits.max_voxels) {
    return ResourceLimit(".pdag geometry holds " + std::to_string(root_count) + " nodes, more than the " +
                         std::to_string(limits.max_voxels) + " this decoder allows");
  }
  out.grid.morton = out.dag.MortonCodes();
  if (out.grid.morton.size() != voxels) return Corrupt(".pdag metadata voxel count disagrees with its geometry");
  if (!file.colors.empty()) {
    const bool voxel_colors_only = (file.colors[0] & kVoxelColorsOnly) != 0;
    if (voxel_colors_only && out.dag.mode != CountMode::kMipmap) {
      return Corrupt(".pdag colors section marks voxel colors only (codec bit 7) in leaf mode");
    }
    if (out.dag.mode == CountMode::kMipmap && !voxel_colors_only) {
      ASSIGN_OR_RETURN(out.mip_colors, DecodeColors(file.colors, root_count));
      ASSIGN_OR_RETURN(out.grid.colors, MipVoxelColors(out.grid.morton, out.grid.depth, out.mip_colors));
    } else {
      ASSIGN_OR_RETURN(out.grid.colors, DecodeColors(file.colors, voxels, out.grid.morton));
    }
  }
  return out;
}

}  // namespace pointdag
