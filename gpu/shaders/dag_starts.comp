#version 450
#extension GL_GOOGLE_include_directive : require
// DAG level, step 2 (after voxel_scan over the tile counts), one invocation per tile of the level
// below: each cell's key and its first entry below.
#include "dag_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint tile = gl_GlobalInvocationID.x;
  if (tile >= params.tiles) return;
  uint cell = counts[tile] - 1u;  // wraps for tile 0, whose first entry is a head
  for (uint i = tile * kTile; i < TileEnd(tile); ++i) {
    if (!Head(i)) continue;
    ++cell;
    firsts[cell] = i;
    keys[cell] = below_keys[i] >> params.shift;
  }
}
