#include "pointdag/tiles3d/tile_content.h"

#include <algorithm>

#include "pointdag/tiles3d/glb_writer.h"

namespace pointdag {
namespace {

StatusOr<VoxelGrid> DecodeTile(std::span<const uint8_t> pdag, int tile_depth, bool colors) {
  ASSIGN_OR_RETURN(PdagFile file, ParsePdag(pdag));
  if (!colors) file.colors.clear();
  DecodeLimits limits;
  limits.max_voxels = std::min(limits.max_voxels, uint64_t{1} << (3 * tile_depth));
  ASSIGN_OR_RETURN(DecodedPdag decoded, DecodePdag(file, limits));
  if (decoded.grid.depth != tile_depth) {
    return Corrupt("the tile is " + std::to_string(decoded.grid.depth) + " levels deep, not the dataset's " +
                   std::to_string(tile_depth));
  }
  if (decoded.grid.morton.empty()) return Corrupt("the tile holds no voxels");
  return std::move(decoded.grid);
}

}  // namespace

StatusOr<TileContent> TranscodeTile(const TileKey& key, std::span<const uint8_t> pdag, int tile_depth) {
  ASSIGN_OR_RETURN(const VoxelGrid grid, DecodeTile(pdag, tile_depth, true));
  TileContent out{MeasureTile(key, grid.morton, tile_depth), {}};
  ASSIGN_OR_RETURN(out.glb, WriteTileGlb(grid));
  return out;
}

StatusOr<TileBox> MeasureStoredTile(const TileKey& key, std::span<const uint8_t> pdag, int tile_depth) {
  ASSIGN_OR_RETURN(const VoxelGrid grid, DecodeTile(pdag, tile_depth, false));
  return MeasureTile(key, grid.morton, tile_depth);
}

}  // namespace pointdag
