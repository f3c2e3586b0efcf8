#version 450
#extension GL_GOOGLE_include_directive : require
// Block encoder, IIB's block tree: level L starts from level L - 1's blocks fitted with L bits per
// weight. One invocation per block.
#include "block_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint m = gl_WorkGroupID.y, k = gl_GlobalInvocationID.x, level = params.level;
  const uint n = counts[CountAt(m, level - 1u)];
  if (k >= n) return;
  const uvec4 c = cand[CandAt(m, level - 1u, k)];
  const Fit f = FitBlock(m, c.x, Length(c), int(params.bits), 0xFFFFFFFFFFFFFFFFul);
  cand[CandAt(m, level, k)] = uvec4(c.x, Length(c), f.a, f.b);
  cost[CandAt(m, level, k)] = WeighedError(m, c.x, Length(c), int(params.bits), f);
  if (k == 0u) counts[CountAt(m, level)] = n;
}
