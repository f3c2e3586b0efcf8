#version 450
#extension GL_GOOGLE_include_directive : require
// DAG level, step 1, one invocation per tile of the level below: how many cells start in it.
#include "dag_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint tile = gl_GlobalInvocationID.x;
  if (tile >= params.tiles) return;
  uint heads = 0u;
  for (uint i = tile * kTile; i < TileEnd(tile); ++i) heads += Head(i) ? 1u : 0u;
  counts[tile] = heads;
}
