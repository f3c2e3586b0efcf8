// 3D Tiles 1.1: the tileset.json of a dataset, from its description and its tiles' tight boxes.
//
// Contract:
//   asset.version "1.1"; one explicit tile per stored LOD tile, in the tile tree of
//   codec/pointdag/tile/tiler.h (children of (l, x, y, z) are (l+1, 2x+i, 2y+j, 2z+k), sorted by key).
//   root.transform: the dataset's ENU->ECEF matrix (column-major) when it is georeferenced, else
//     the identity, with a note in asset.extras.pointdag (coordinates are then the scan's own units).
//   boundingVolume.box: the tile's occupied voxels (not their cube), in the dataset frame (z-up).
//   geometricError: a level-l tile is drawn at level l's voxel size, voxel_size * 2^(L-l), so that
//     is its error; the finest level's is 0; the tileset's is twice the root's.
//   refine "REPLACE" (on the root, inherited below); content.uri "{level}/{x}/{y}/{z}.glb",
//     relative to the tileset.
// The text depends on the inputs alone, so the daemon and the CLI write the same bytes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pointdag/tile/tiler.h"

namespace pointdag {

// What a tileset needs of a dataset (GET /v1/datasets/{id}, proto/PROTOCOL.md §2).
struct TilesetDataset : TileGridShape {
  std::optional<std::array<double, 16>> enu_to_ecef;  // column-major; absent without a CRS

  double LevelVoxelSize(int level) const;
};

// From the dataset's JSON (which may come from a server: every member is range-checked, kMalformed).
StatusOr<TilesetDataset> ParseTilesetDataset(const nlohmann::json& dataset);

// A tile's occupied cells, inclusive, in its level's global cell coordinates (key * 2^T + local).
struct TileBox {
  TileKey key;
  std::array<uint32_t, 3> min{}, max{};
};

// The box of a tile's voxels (Morton codes local to the tile, at most tile_depth levels); the
// codes must not be empty.
TileBox MeasureTile(const TileKey& key, std::span<const uint64_t> local_morton, int tile_depth);

// The box of a TileBox in the dataset frame: {min x, y, z, max x, y, z}.
std::array<double, 6> BoxInFrame(const TilesetDataset& dataset, const TileBox& box);

// "{level}/{x}/{y}/{z}.glb": a tile's content, relative to the tileset.
std::string ContentUri(const TileKey& key);

// kInvalidArgument when the tiles are not one tree rooted at (0, 0, 0, 0), or lie outside the levels.
StatusOr<std::string> BuildTileset(const TilesetDataset& dataset, std::vector<TileBox> tiles);

}  // namespace pointdag
