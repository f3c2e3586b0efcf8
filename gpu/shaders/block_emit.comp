#version 450
#extension GL_GOOGLE_include_directive : require
// Block encoder, last step, one invocation per macro block: the coded blocks in order of their
// start (IIB: the marks left by block_cut and block_open; IIA: level 0 at 3 bits), and their count.
#include "block_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint m = gl_GlobalInvocationID.x;
  if (m >= params.macros) return;
  const uint out_at = m * kMacro, n = MacroColors(m);
  uint emitted = 0u;
  if (params.fixed_rate != 0u) {
    for (; emitted < counts[CountAt(m, 0u)]; ++emitted) {
      const uvec4 c = cand[CandAt(m, 0u, emitted)];
      blocks[out_at + emitted] = uvec4(out_at + c.x, Length(c), (c.z & 0xFFFFFFu) | (3u << 24), c.w);
    }
  } else {
    for (uint pos = 0u; pos < n; ++emitted) {
      const uvec4 mark = pair[out_at + pos];
      if (mark.x == 0u || mark.x > kLevels) break;  // not a cover: the host sees the short count
      const uint level = mark.x - 1u;
      const uvec4 c = cand[CandAt(m, level, mark.y)];
      blocks[out_at + emitted] = uvec4(out_at + c.x, Length(c), (c.z & 0xFFFFFFu) | (level << 24), c.w);
      pos += Length(c);
    }
  }
  blocks[params.macros * kMacro + m] = uvec4(emitted, 0u, 0u, 0u);
}
