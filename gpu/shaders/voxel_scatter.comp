#version 450
#extension GL_GOOGLE_include_directive : require
// Radix pass, step 3, one invocation per tile: each key (and its point) to its place, in tile order
// within a digit, which keeps the sort stable as LSD radix sorting needs.
#include "voxel_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint tile = gl_GlobalInvocationID.x;
  if (tile >= params.tiles) return;
  for (uint i = tile * kTile; i < TileEnd(tile); ++i) {
    const uvec2 key = src_keys[i];
    const uint digit = uint((uint64_t(key.x) | (uint64_t(key.y) << 32)) >> params.shift) & 255u;
    const uint at = counts[kDigits * params.tiles + digit] + counts[digit * params.tiles + tile]++;
    dst_keys[at] = key;
    dst_points[at] = src_points[i];
  }
}
