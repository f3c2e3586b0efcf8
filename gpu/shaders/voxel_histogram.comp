#version 450
#extension GL_GOOGLE_include_directive : require
// Radix pass, step 1, one invocation per tile: how many of its keys have each digit.
#include "voxel_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint tile = gl_GlobalInvocationID.x;
  if (tile >= params.tiles) return;
  for (uint d = 0u; d < kDigits; ++d) counts[d * params.tiles + tile] = 0u;
  for (uint i = tile * kTile; i < TileEnd(tile); ++i) {
    const uvec2 key = src_keys[i];
    const uint digit = uint((uint64_t(key.x) | (uint64_t(key.y) << 32)) >> params.shift) & 255u;
    ++counts[digit * params.tiles + tile];
  }
}
