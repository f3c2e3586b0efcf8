#version 450
#extension GL_GOOGLE_include_directive : require
// Reduction, step 3, one invocation per tile of voxels: the mean color, rounded half up, in 8 bits
// (sum / (points x divisor), divisor 257 scaling 16-bit sources).
#include "voxel_common.glsl"
layout(local_size_x = 64) in;

uint Mean(uint at, uint64_t divisor) {
  const uint64_t sum = uint64_t(sums[at]) | (uint64_t(sums[at + 1u]) << 32);
  return uint(min((2ul * sum + divisor) / (2ul * divisor), 255ul));
}

void main() {
  const uint first = gl_GlobalInvocationID.x * kTile, total = counts[params.tiles];
  for (uint v = first; v < min(total, first + kTile); ++v) {
    const uint64_t divisor = uint64_t(sums[v * 7u + 6u]) * uint64_t(params.divisor);
    voxels[v].z = Mean(v * 7u, divisor) | (Mean(v * 7u + 2u, divisor) << 8) | (Mean(v * 7u + 4u, divisor) << 16);
  }
}
