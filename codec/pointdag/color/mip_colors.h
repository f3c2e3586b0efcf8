// Stage 5c: mipmapped colors (Paper IIB). With the DAG in mipmap mode every node has a color index
// (its depth-first pre-order rank, Svdag::MipColorIndex), so the color array lists every node of the
// octree in pre-order: a node's color is the rounded mean of its children's colors, a voxel's is its
// own. Coded by the same block codecs: nodes of one level stay close to their neighbours in the
// order, so the array is as coherent as the voxels' own.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/status.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

struct MipColors {
  std::vector<Rgb8> colors;           // every node, pre-order
  std::vector<uint64_t> voxel_index;  // pre-order index of each voxel, in Morton order
};

// `morton` sorted and unique on a depth-`depth` grid; `colors` parallel to it.
MipColors BuildMipColors(std::span<const uint64_t> morton, std::span<const Rgb8> colors, int depth);

// Just the pre-order index of each voxel (to read voxel colors out of decoded mip colors).
std::vector<uint64_t> MipVoxelIndices(std::span<const uint64_t> morton, int depth);

// The voxels' own colors out of decoded mip colors (MipVoxelIndices without the index array).
// Corrupt when a voxel's index falls outside `mip_colors` (hostile counts).
StatusOr<std::vector<Rgb8>> MipVoxelColors(std::span<const uint64_t> morton, int depth, std::span<const Rgb8> mip_colors);

}  // namespace pointdag
