#version 450
#extension GL_GOOGLE_include_directive : require
// Radix pass, step 2, one invocation per digit: where each tile's keys with this digit start among
// the digit's keys, and the digit's total after the table.
#include "voxel_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint digit = gl_GlobalInvocationID.x;
  if (digit >= kDigits) return;
  uint total = 0u;
  for (uint tile = 0u; tile < params.tiles; ++tile) {
    const uint n = counts[digit * params.tiles + tile];
    counts[digit * params.tiles + tile] = total;
    total += n;
  }
  counts[kDigits * params.tiles + digit] = total;
}
