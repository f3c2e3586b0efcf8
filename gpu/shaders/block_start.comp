#version 450
#extension GL_GOOGLE_include_directive : require
// Block encoder, step 1, one invocation per macro block: prefix sums of its colors and of their
// products (BlockFitter's constructor), and one candidate block per color at level 0.
#include "block_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint m = gl_GlobalInvocationID.x;
  if (m >= params.macros) return;
  const uint n = MacroColors(m), base = m * (kMacro + 1u) * 9u;
  prefix[base] = prefix[base + 1u] = prefix[base + 2u] = prefix[base + 3u] = prefix[base + 4u] = 0u;
  prefix[base + 5u] = prefix[base + 6u] = prefix[base + 7u] = prefix[base + 8u] = 0u;
  for (uint i = 0; i < n; ++i) {
    const uint packed = colors[m * kMacro + i];
    const uvec3 c = uvec3(Unpack(packed));
    const uint from = base + i * 9u, to = from + 9u;
    prefix[to] = prefix[from] + c.r;
    prefix[to + 1u] = prefix[from + 1u] + c.g;
    prefix[to + 2u] = prefix[from + 2u] + c.b;
    prefix[to + 3u] = prefix[from + 3u] + c.r * c.r;
    prefix[to + 4u] = prefix[from + 4u] + c.g * c.g;
    prefix[to + 5u] = prefix[from + 5u] + c.b * c.b;
    prefix[to + 6u] = prefix[from + 6u] + c.r * c.g;
    prefix[to + 7u] = prefix[from + 7u] + c.r * c.b;
    prefix[to + 8u] = prefix[from + 8u] + c.g * c.b;
    cand[CandAt(m, 0u, i)] = uvec4(i, 1u, packed, packed);  // a single color fits itself exactly
    cost[CandAt(m, 0u, i)] = 0ul;
  }
  counts[CountAt(m, 0u)] = n;
}
