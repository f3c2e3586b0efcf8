#version 450
#extension GL_GOOGLE_include_directive : require
// Reduction, step 2, one invocation per tile: each voxel's code, and its points' color sums and
// count. A voxel whose points span tiles gets a part from each, added atomically: 64-bit sums as
// two words, the carry added when the low word wraps.
#include "voxel_common.glsl"
layout(local_size_x = 64) in;

void AddWide(uint at, uint64_t value) {
  const uint low = uint(value), old = atomicAdd(sums[at], low);
  const uint carry = old + low < old ? 1u : 0u;
  if (uint(value >> 32) + carry != 0u) atomicAdd(sums[at + 1u], uint(value >> 32) + carry);
}

void Flush(uint voxel, u64vec3 sum, uint points) {
  if (points == 0u) return;
  AddWide(voxel * 7u, sum.x);
  AddWide(voxel * 7u + 2u, sum.y);
  AddWide(voxel * 7u + 4u, sum.z);
  atomicAdd(sums[voxel * 7u + 6u], points);
}

void main() {
  const uint tile = gl_GlobalInvocationID.x;
  if (tile >= params.tiles) return;
  uint voxel = counts[tile] - 1u;  // wraps for tile 0, whose first key is a head
  u64vec3 sum = u64vec3(0ul);
  uint points = 0u;
  for (uint i = tile * kTile; i < TileEnd(tile); ++i) {
    const uvec2 key = src_keys[i];
    if (i == 0u || !SameKey(key, src_keys[i - 1u])) {
      Flush(voxel, sum, points);
      ++voxel;
      sum = u64vec3(0ul);
      points = 0u;
      voxels[voxel].xy = key;
    }
    const uvec2 c = colors[src_points[i]];
    sum += u64vec3(c.x & 0xFFFFu, c.x >> 16, c.y);
    ++points;
  }
  Flush(voxel, sum, points);
}
