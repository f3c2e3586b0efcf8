// 3D Tiles content: one decoded LOD tile as a glTF 2.0 binary (.glb) of points.
//
// Contract: one scene, one node, one mesh with one primitive of mode 0 (POINTS), one point per
// voxel in the tile's Morton order.
//   POSITION: the voxel's integer cell (i, j, k), unsigned short, not normalized, VEC3 at an
//     8-byte stride (legal through KHR_mesh_quantization), with min/max.
//   COLOR_0: the voxel's color, linear as glTF defines vertex colors: each stored sRGB byte through
//     the inverse sRGB transfer function (LinearColor16), normalized unsigned short VEC3 at an 8-byte
//     stride (8 bits of linear color would band the darks); absent when the tile has no colors.
//   Both vertex streams are compressed with EXT_meshopt_compression (mode ATTRIBUTES, filter
//     NONE, vertex codec version 0, the only one that extension allows) into the GLB's BIN chunk
//     (buffer 0); their bufferViews point into buffer 1, the fallback buffer with no data
//     ({fallback: true}), as the extension requires. Both extensions are used and required.
//   The node's matrix places the cells: glTF is y-up and 3D Tiles turns glTF content z-up at run
//     time ((x, y, z) -> (x, -z, y)), so the node maps a cell c to
//     (wx, wz, -wy), w = tile origin + (c + 0.5) * voxel size, and the runtime's turn gives back
//     w, the voxel's centre in the dataset frame.
// The bytes depend on the grid alone (same grid, same bytes), so the daemon and the CLI agree.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

// An sRGB byte as the 16-bit linear value COLOR_0 stores: round(65535 * linear(srgb / 255)).
uint16_t LinearColor16(uint8_t srgb);

// The node matrix (column-major) that WriteTileGlb writes for a tile with this origin and voxel size.
std::array<double, 16> TileNodeMatrix(const std::array<double, 3>& origin, double voxel_size);

// kInvalidArgument for an empty tile, a depth above 16 (cells would not fit unsigned short) or
// colors not parallel to the voxels.
StatusOr<std::vector<uint8_t>> WriteTileGlb(const VoxelGrid& tile);

}  // namespace pointdag
