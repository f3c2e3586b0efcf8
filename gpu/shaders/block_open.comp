#version 450
#extension GL_GOOGLE_include_directive : require
// Block encoder, IIB's cut, top-down, one level per dispatch (params.level = the parents' level)
// and one invocation per macro block: a block is open when its parent is open and not kept; open
// and kept blocks are the ones coded, marked for emission at their start.
#include "block_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint m = gl_GlobalInvocationID.x, level = params.level;
  if (m >= params.macros) return;
  const uint n = counts[CountAt(m, level - 1u)];
  uint parent = 0u;
  for (uint k = 0u; k < n; ++k) {
    uvec4 c = cand[CandAt(m, level - 1u, k)];
    // Every parent holds at least one child, so one step reaches the next parent.
    const uvec4 p = cand[CandAt(m, level, parent)];
    const uint parent_z = p.x + Length(p) <= c.x ? cand[CandAt(m, level, ++parent)].z : p.z;
    if ((parent_z & kOpen) == 0u || (parent_z & kKeep) != 0u) continue;
    cand[CandAt(m, level - 1u, k)].z = c.z | kOpen;
    if ((c.z & kKeep) != 0u) pair[m * kMacro + c.x] = uvec4(level, k, 0u, 0u);
  }
}
