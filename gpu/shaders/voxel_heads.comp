#version 450
#extension GL_GOOGLE_include_directive : require
// Reduction, step 1, one invocation per tile of the sorted keys: how many voxels start in it.
#include "voxel_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint tile = gl_GlobalInvocationID.x;
  if (tile >= params.tiles) return;
  uint heads = 0u;
  for (uint i = tile * kTile; i < TileEnd(tile); ++i) heads += (i == 0u || !SameKey(src_keys[i], src_keys[i - 1u])) ? 1u : 0u;
  counts[tile] = heads;
}
