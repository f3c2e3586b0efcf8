// A stored LOD tile (the .pdag bytes that GET .../tiles/... serves) as 3D Tiles: its .glb content
// (glb_writer.h) and its tight box for the tileset (tileset.h).
//
// Contract: the tile is decoded with limits set by the tile's cube (2^(3 T) voxels, T the
// dataset's tile depth), whatever its metadata says, and must be T levels deep (kCorrupt if not);
// the container's and decoders' own errors pass through. The daemon and the CLI both call these,
// so they transcode the same tile to the same bytes.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/tiles3d/tileset.h"

namespace pointdag {

struct TileContent {
  TileBox box;
  std::vector<uint8_t> glb;
};
// Geometry and colors -> glTF binary, and the box (one decode for both).
StatusOr<TileContent> TranscodeTile(const TileKey& key, std::span<const uint8_t> pdag, int tile_depth);

// Geometry only (the colors are not decoded) -> the tile's box.
StatusOr<TileBox> MeasureStoredTile(const TileKey& key, std::span<const uint8_t> pdag, int tile_depth);

}  // namespace pointdag
