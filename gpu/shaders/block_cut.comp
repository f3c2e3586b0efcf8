#version 450
#extension GL_GOOGLE_include_directive : require
// Block encoder, IIB's cut, bottom-up, one level per dispatch and one invocation per macro block:
// a block's cost is its own (kTenthsPerSse x its error + scaled x its tenths of a bit) or its
// children's, whichever is less (kKeep where its own; ties: the children). At the top level every
// block is open, and the kept ones are marked for emission at their start.
#include "block_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint m = gl_GlobalInvocationID.x, level = params.level;
  if (m >= params.macros) return;
  const uint n = counts[CountAt(m, level)];
  uint child = 0u;
  for (uint k = 0u; k < n; ++k) {
    const uvec4 c = cand[CandAt(m, level, k)];
    const uint64_t own = kTenthsPerSse * cost[CandAt(m, level, k)] + Scaled() * RateTenths(Length(c), level);
    uint64_t children = 0xFFFFFFFFFFFFFFFFul;
    if (level > 0u) {
      const uint stop = c.x + Length(c), below = counts[CountAt(m, level - 1u)];
      for (children = 0ul; child < below && cand[CandAt(m, level - 1u, child)].x < stop; ++child) children += cost[CandAt(m, level - 1u, child)];
    }
    cost[CandAt(m, level, k)] = min(own, children);
    cand[CandAt(m, level, k)].z = (c.z & 0xFFFFFFu) | (own < children ? kKeep : 0u);
  }
  if (level != kLevels - 1u) return;
  for (uint k = 0u; k < n; ++k) {
    const uint z = cand[CandAt(m, level, k)].z | kOpen;
    cand[CandAt(m, level, k)].z = z;
    if ((z & kKeep) != 0u) pair[m * kMacro + cand[CandAt(m, level, k)].x] = uvec4(1u + level, k, 0u, 0u);
  }
}
