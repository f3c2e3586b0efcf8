#version 450
#extension GL_GOOGLE_include_directive : require
// One invocation: exclusive prefix sum of counts[shift .. shift + n) in place, total at shift + n
// (digit bases of a radix pass; voxels before each tile in the reduction).
#include "voxel_common.glsl"
layout(local_size_x = 1) in;

void main() {
  uint total = 0u;
  for (uint i = params.shift; i < params.shift + params.divisor; ++i) {
    const uint n = counts[i];
    counts[i] = total;
    total += n;
  }
  counts[params.shift + params.divisor] = total;
}
