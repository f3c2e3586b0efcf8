// Stage 7: an octree of LOD tiles over the voxel cube.
//
// Contract: the finest voxels (depth D, sorted Morton codes) are cut into levels 0..L, L = D - T,
// where T = min(8, D) is the tile depth: every tile spans 2^T voxels per side. Level l is the whole
// scan at voxel size finest * 2^(L-l); its voxel codes are the finest codes shifted right by 3(L-l)
// bits, with the exact mean color of the finest voxels each covers. Tile (l, x, y, z) holds the
// level-l voxels whose top 3l code bits are (x, y, z) interleaved; its children are the eight
// tiles (l+1, 2x+i, 2y+j, 2z+k) at twice the resolution (replace refinement). Each tile is a
// self-contained .pdag (proto/PDAG_FORMAT.md) with mipmapped colors, its world origin and voxel
// size in its metadata, and a "tile" member {level, x, y, z}. Empty tiles do not exist.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "pointdag/color/block_stream.h"
#include "pointdag/container/json_fields.h"
#include "pointdag/pipeline.h"

namespace pointdag {

struct TileKey {
  int level = 0;
  uint32_t x = 0, y = 0, z = 0;
  friend bool operator==(const TileKey&, const TileKey&) = default;
  friend auto operator<=>(const TileKey&, const TileKey&) = default;
};

struct Tile {
  TileKey key;
  uint64_t voxels = 0;
  std::vector<uint8_t> bytes;  // a serialized .pdag
};

struct TilingOptions {
  int tile_depth = 8;
  // Tiles are decoded by every client on every view: they take geometry coder 3, whose masks decode
  // by table lookup, 2.4-3.2x the tile decode rate of coder 2 version 2 for 10-15 % more tile bytes
  // (docs/benchmarks.md, "Tile stream for decode speed").
  // Version 7 reads the back-references by table lookup too (IGN 0.1 m: geometry +1.1 %, decode
  // -2.4 ms of 12.8), and their block colors take stream version 6, whose weights are read a group at
  // a time in codes fixed in the format (colors +0..4 %, decode -24 %): docs/benchmarks.md, "fixship".
  GeometryCoder geometry_coder = GeometryCoder::kTable;
  int geometry_version = kPrefixRefsStreamVersion;
  ColorEncodeOptions colors{.codec = ColorCodec::kVariableRate, .target_psnr_y = 38.0, .block_version = kFixedWeightCodesVersion};
  ProgressFn progress;  // (tiles done, tiles total)
};

struct TileSet {
  int levels = 0;      // L + 1
  int tile_depth = 0;  // T
  std::vector<Tile> tiles;  // sorted by key
  uint64_t stored_bytes() const;
};

// `finest` holds the voxels at the finest level; `scan` and `source_name` go into each tile's metadata.
StatusOr<TileSet> BuildTiles(const VoxelGrid& finest, const ScanInfo& scan, const std::string& source_name,
                             const TilingOptions& options);

// The LOD grid a dataset description declares (GET /v1/datasets/{id}, proto/PROTOCOL.md §2): what a
// client needs to place tiles. The description may come from a server, so every member is
// range-checked: 2 <= tile_depth <= 8, 1 <= levels, levels - 1 + tile_depth <= 21, voxel_size > 0.
struct TileGridShape {
  int levels = 0;      // L + 1
  int tile_depth = 0;  // T
  std::array<double, 3> origin{};  // bounds.min: the voxel cube's corner in the dataset frame
  double voxel_size = 0;           // finest level
};
// kMalformed (or the code `description` was made with) naming the member.
StatusOr<TileGridShape> ReadTileGridShape(const JsonFields& description);

// The voxels of one level (codes of depth T + level, mean colors), as BuildTiles cuts them.
VoxelGrid LevelGrid(const VoxelGrid& finest, int level, int tile_depth);

}  // namespace pointdag
