#version 450
#extension GL_GOOGLE_include_directive : require
// Block encoder, first half of a merge pass: whether each block of a level merges with its right
// neighbour, one invocation per block: within the threshold (IIA), or adding less error than the
// header it saves is worth (IIB, VariableRateMacroBlock). A pair that failed before and has not
// changed since is not fitted again (MergePasses' failed_with).
#include "block_common.glsl"
layout(local_size_x = 64) in;

void main() {
  const uint m = gl_WorkGroupID.y, k = gl_GlobalInvocationID.x, level = params.level;
  if (k + 1u >= counts[CountAt(m, level)]) return;
  const uvec4 here = cand[CandAt(m, level, k)], next = cand[CandAt(m, level, k + 1u)];
  uvec4 result = uvec4(0u);
  if (FailedWith(here) != Length(next)) {
    const uint length = Length(here) + Length(next);
    const uint64_t saved = Scaled() * uint64_t(kHeaderTenths + (params.bits != 0u ? kSecondEndTenths : 0u)) / kTenthsPerSse;
    const uint64_t limit = params.fixed_rate != 0u ? MaxSse(length)
                                                   : cost[CandAt(m, level, k)] + cost[CandAt(m, level, k + 1u)] + saved;
    const Fit f = FitBlock(m, here.x, length, int(params.bits), limit);
    // Variable rate: the merged block's weighed error within the limit too (f.sse bounds it from below).
    const uint64_t e = params.fixed_rate != 0u || f.sse > limit ? f.sse : WeighedError(m, here.x, length, int(params.bits), f);
    if (e <= limit) result = uvec4(1u + uint(e >> 32), f.a, f.b, uint(e));
  }
  pair[m * kMacro + k] = result;
}
