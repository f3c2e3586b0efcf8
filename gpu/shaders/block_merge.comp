#version 450
#extension GL_GOOGLE_include_directive : require
// Block encoder, second half of a merge pass, one invocation per macro block: walk the level's
// blocks left to right, merging a block with its right neighbour where block_pairs found that the
// pair passes, at most once per block (MergePasses). Counts the macro blocks that merged anything.
#include "block_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint m = gl_GlobalInvocationID.x, level = params.level;
  if (m >= params.macros) return;
  const uint n = counts[CountAt(m, level)];
  uint out_n = 0u;
  bool merged = false;
  for (uint i = 0u; i < n; ++i) {
    uvec4 here = cand[CandAt(m, level, i)];
    if (i + 1u < n) {
      const uint next_length = Length(cand[CandAt(m, level, i + 1u)]);
      const uvec4 p = pair[m * kMacro + i];
      if (p.x != 0u) {
        cost[CandAt(m, level, out_n)] = (uint64_t(p.x - 1u) << 32) | uint64_t(p.w);
        cand[CandAt(m, level, out_n++)] = uvec4(here.x, Length(here) + next_length, p.y, p.z);
        merged = true;
        ++i;
        continue;
      }
      here.y = Length(here) | (next_length << 16);  // failed (now or before) with this neighbour
    }
    cost[CandAt(m, level, out_n)] = cost[CandAt(m, level, i)];
    cand[CandAt(m, level, out_n++)] = here;
  }
  counts[CountAt(m, level)] = out_n;
  if (merged) atomicAdd(merges[params.slot], 1u);
}
