#version 450
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
// Block color encoder (Papers IIA/IIB), one workgroup per 16K-color macro block.
// The same integer steps in the same order as codec/pointdag/color/block_fit.cc (BlockFitter::Fit,
// FitWeights) and block_codec.cc (MergePasses, VariableRateMacroBlock), so that the blocks, and
// the .pdag bytes, come out identical. Status: on lavapipe they match for uniform colors
// (gpu_test) but not yet for varied ones, so the codec does not call this kernel yet (issue #5).
// (block_fit.cc's CannotReach only skips fits that would fail: it has no twin here.)
layout(local_size_x = 1) in;

layout(push_constant) uniform Params {
  uint count;          // colors in all
  uint fixed_rate;     // 1: IIA, 3 bits everywhere; 0: IIB variable rate
  uint threshold_lo;   // Threshold::scaled, low and high words
  uint threshold_hi;
} params;

const uint kMacro = 16384u;
const uint kLevels = 5u;  // 0..4 bits per weight

layout(std430, binding = 0) readonly buffer Colors { uint colors[]; };  // r | g << 8 | b << 16
layout(std430, binding = 1) buffer Prefix { uint prefix[]; };           // per macro: (kMacro + 1) x 9 sums
layout(std430, binding = 2) buffer Levels { uvec4 cand[]; };            // per macro: kLevels x kMacro
layout(std430, binding = 3) buffer Costs { uint cost[]; };              // parallel to cand
layout(std430, binding = 4) buffer Blocks { uvec4 blocks[]; };          // per macro: kMacro
layout(std430, binding = 5) buffer Counts { uint block_count[]; };      // per macro

// A candidate: x start, y length | failed_with << 16, z endpoint A | keep << 24 | open << 25, w endpoint B.
uint g_macro, g_colors, g_prefix_base, g_cand_base;
// Per-level block counts and cursors live in shared memory: lavapipe (Mesa 22.3) miscompiles
// dynamically indexed private arrays in this shader.
shared uint counts[kLevels], cursor[kLevels];

int64_t FloorDiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
int64_t RoundDiv(int64_t a, int64_t b) { return FloorDiv(2 * a + b, 2 * b); }
uint Clamp255(int64_t v) { return v < 0 ? 0u : (v > 255 ? 255u : uint(v)); }
int64_t Abs64(int64_t v) { return v < 0 ? -v : v; }
int BitWidth(uint64_t x) {
  const uint hi = uint(x >> 32);
  return hi != 0u ? findMSB(hi) + 33 : findMSB(uint(x)) + 1;
}
ivec3 Unpack(uint c) { return ivec3(int(c & 255u), int((c >> 8) & 255u), int((c >> 16) & 255u)); }
uint Pack(uint r, uint g, uint b) { return r | (g << 8) | (b << 16); }
uint ColorAt(uint i) { return colors[g_macro * kMacro + i]; }

uint64_t MaxSse(uint length) {
  const uint64_t scaled = uint64_t(params.threshold_lo) | (uint64_t(params.threshold_hi) << 32);
  return uint64_t(length) * scaled / 1024ul;
}

void Shrink(inout i64vec3 v) {
  const int64_t largest = max(max(Abs64(v.x), Abs64(v.y)), Abs64(v.z));
  const int shift = max(0, BitWidth(uint64_t(largest)) - 10);
  v = v >> shift;
}

uint WeightOf(ivec3 c, ivec3 a, ivec3 d, int len2, int m) {
  const int dot_ = (c.x - a.x) * d.x + (c.y - a.y) * d.y + (c.z - a.z) * d.z;
  if (dot_ <= 0) return 0u;
  if (dot_ >= len2) return uint(m);
  return uint((2 * m * dot_ + len2) / (2 * len2));
}

uint ErrorOf(ivec3 c, ivec3 a, ivec3 b, uint w, uint m) {
  const uvec3 r = (uvec3(a) * (m - w) + uvec3(b) * w + m / 2u) / m;
  const ivec3 e = c - ivec3(r);
  return uint(e.x * e.x + e.y * e.y + e.z * e.z);
}

struct Fit {
  uint a, b;
  uint64_t sse;
};

// BlockFitter::Fit and FitWeights. Written with vector components, not indexed arrays: lavapipe
// (Mesa 22.3) miscompiles dynamically indexed private arrays here.
Fit FitBlock(uint begin, uint length, int bits, uint64_t give_up_above) {
  const int64_t n = int64_t(length);
  const uint lo_at = g_prefix_base + begin * 9u, hi_at = g_prefix_base + (begin + length) * 9u;
  const i64vec3 s = i64vec3(int64_t(prefix[hi_at]) - int64_t(prefix[lo_at]), int64_t(prefix[hi_at + 1u]) - int64_t(prefix[lo_at + 1u]),
                            int64_t(prefix[hi_at + 2u]) - int64_t(prefix[lo_at + 2u]));
  // Squares rr gg bb and products rg rb gb.
  const i64vec3 sq = i64vec3(int64_t(prefix[hi_at + 3u]) - int64_t(prefix[lo_at + 3u]), int64_t(prefix[hi_at + 4u]) - int64_t(prefix[lo_at + 4u]),
                             int64_t(prefix[hi_at + 5u]) - int64_t(prefix[lo_at + 5u]));
  const i64vec3 pr = i64vec3(int64_t(prefix[hi_at + 6u]) - int64_t(prefix[lo_at + 6u]), int64_t(prefix[hi_at + 7u]) - int64_t(prefix[lo_at + 7u]),
                             int64_t(prefix[hi_at + 8u]) - int64_t(prefix[lo_at + 8u]));
  // Covariance scaled by n^2, by columns (symmetric).
  const i64vec3 c0 = i64vec3(n * sq.x - s.x * s.x, n * pr.x - s.y * s.x, n * pr.y - s.z * s.x);
  const i64vec3 c1 = i64vec3(n * pr.x - s.x * s.y, n * sq.y - s.y * s.y, n * pr.z - s.z * s.y);
  const i64vec3 c2 = i64vec3(n * pr.y - s.x * s.z, n * pr.z - s.y * s.z, n * sq.z - s.z * s.z);
  const int widest = c0.x >= c1.y ? (c0.x >= c2.z ? 0 : 2) : (c1.y >= c2.z ? 1 : 2);
  const int64_t widest_var = widest == 0 ? c0.x : (widest == 1 ? c1.y : c2.z);
  if (bits == 0 || widest_var == 0) {
    const i64vec3 a = i64vec3(RoundDiv(s.x, n), RoundDiv(s.y, n), RoundDiv(s.z, n));
    const i64vec3 e = sq - 2 * a * s + n * a * a;
    const uint c = Pack(Clamp255(a.x), Clamp255(a.y), Clamp255(a.z));
    return Fit(c, c, uint64_t(e.x) + uint64_t(e.y) + uint64_t(e.z));
  }
  i64vec3 axis = widest == 0 ? c0 : (widest == 1 ? c1 : c2);
  Shrink(axis);
  for (int iter = 0; iter < 8; ++iter) {
    // cov * axis, cov symmetric: row j = column j. (Not dot(): GLSL's dot() is floating point.)
    i64vec3 next = i64vec3(c0.x * axis.x + c0.y * axis.y + c0.z * axis.z, c1.x * axis.x + c1.y * axis.y + c1.z * axis.z,
                          c2.x * axis.x + c2.y * axis.y + c2.z * axis.z);
    if (next.x == 0 && next.y == 0 && next.z == 0) break;
    Shrink(next);
    axis = next;
  }
  int64_t lo = 0, hi = 0;
  for (uint i = 0; i < length; ++i) {
    const i64vec3 c = i64vec3(Unpack(ColorAt(begin + i)));
    const i64vec3 d = n * c - s;
    const int64_t t = d.x * axis.x + d.y * axis.y + d.z * axis.z;
    lo = min(lo, t);
    hi = max(hi, t);
  }
  const int64_t axis2 = axis.x * axis.x + axis.y * axis.y + axis.z * axis.z;
  const int64_t den = n * axis2;
  Fit best = Fit(Pack(Clamp255(RoundDiv(s.x * axis2 + lo * axis.x, den)), Clamp255(RoundDiv(s.y * axis2 + lo * axis.y, den)),
                      Clamp255(RoundDiv(s.z * axis2 + lo * axis.z, den))),
                 Pack(Clamp255(RoundDiv(s.x * axis2 + hi * axis.x, den)), Clamp255(RoundDiv(s.y * axis2 + hi * axis.y, den)),
                      Clamp255(RoundDiv(s.z * axis2 + hi * axis.z, den))),
                 0ul);

  const int m = (1 << bits) - 1;
  const ivec3 a = Unpack(best.a), b = Unpack(best.b), d = b - a;
  const int len2 = d.x * d.x + d.y * d.y + d.z * d.z;
  int64_t s00 = 0, s01 = 0, s11 = 0;
  i64vec3 r0 = i64vec3(0), r1 = i64vec3(0);
  for (uint i = 0; i < length; ++i) {
    const ivec3 c = Unpack(ColorAt(begin + i));
    const uint w = WeightOf(c, a, d, len2, m);
    best.sse += uint64_t(ErrorOf(c, a, b, w, uint(m)));
    const int64_t u = int64_t(m) - int64_t(w), t = int64_t(w);
    s00 += u * u;
    s01 += u * t;
    s11 += t * t;
    r0 += u * i64vec3(c);
    r1 += t * i64vec3(c);
  }
  const int64_t det = s00 * s11 - s01 * s01;
  if (det <= 0 || best.sse == 0) return best;
  const i64vec3 na = int64_t(m) * (s11 * r0 - s01 * r1), nb = int64_t(m) * (s00 * r1 - s01 * r0);
  const uint refined_a = Pack(Clamp255(RoundDiv(na.x, det)), Clamp255(RoundDiv(na.y, det)), Clamp255(RoundDiv(na.z, det)));
  const uint refined_b = Pack(Clamp255(RoundDiv(nb.x, det)), Clamp255(RoundDiv(nb.y, det)), Clamp255(RoundDiv(nb.z, det)));
  if (refined_a == best.a && refined_b == best.b) return best;
  const ivec3 a2 = Unpack(refined_a), b2 = Unpack(refined_b), d2 = b2 - a2;
  const int len2b = d2.x * d2.x + d2.y * d2.y + d2.z * d2.z;
  const uint64_t stop = min(best.sse, give_up_above);
  uint64_t sse = 0;
  for (uint i = 0; i < length && sse <= stop; ++i) {
    const ivec3 c = Unpack(ColorAt(begin + i));
    sse += uint64_t(ErrorOf(c, a2, b2, WeightOf(c, a2, d2, len2b, m), uint(m)));
  }
  if (sse < best.sse) best = Fit(refined_a, refined_b, sse);
  return best;
}

uint CandAt(uint level, uint k) { return g_cand_base + level * kMacro + k; }

// MergePasses, in place over one level's candidates.
uint Merge(uint level, uint n, int bits) {
  bool merged_any = true;
  while (merged_any) {
    merged_any = false;
    uint out_n = 0;
    for (uint i = 0; i < n; ++i) {
      uvec4 ci = cand[CandAt(level, i)];
      if (i + 1 < n) {
        const uvec4 cn = cand[CandAt(level, i + 1)];
        const uint next_length = cn.y & 0xFFFFu;
        if ((ci.y >> 16) != next_length) {
          const uint length = (ci.y & 0xFFFFu) + next_length;
          const uint64_t limit = MaxSse(length);
          const Fit f = FitBlock(ci.x, length, bits, limit);
          if (f.sse <= limit) {
            cand[CandAt(level, out_n++)] = uvec4(ci.x, length, f.a, f.b);
            merged_any = true;
            ++i;
            continue;
          }
          ci.y = (ci.y & 0xFFFFu) | (next_length << 16);
        }
      }
      cand[CandAt(level, out_n++)] = ci;
    }
    n = out_n;
  }
  return n;
}

uint BlockCost(uint length, uint bits) { return 150u + (bits != 0u ? 150u : 0u) + length * bits * 4u; }

void main() {
  g_macro = gl_WorkGroupID.x;
  g_colors = min(kMacro, params.count - g_macro * kMacro);
  g_prefix_base = g_macro * (kMacro + 1u) * 9u;
  g_cand_base = g_macro * kLevels * kMacro;
  for (int k = 0; k < 9; ++k) prefix[g_prefix_base + k] = 0u;
  for (uint i = 0; i < g_colors; ++i) {
    const uvec3 c = uvec3(Unpack(ColorAt(i)));
    const uint from = g_prefix_base + i * 9u, to = from + 9u;
    prefix[to] = prefix[from] + c.r;
    prefix[to + 1u] = prefix[from + 1u] + c.g;
    prefix[to + 2u] = prefix[from + 2u] + c.b;
    prefix[to + 3u] = prefix[from + 3u] + c.r * c.r;
    prefix[to + 4u] = prefix[from + 4u] + c.g * c.g;
    prefix[to + 5u] = prefix[from + 5u] + c.b * c.b;
    prefix[to + 6u] = prefix[from + 6u] + c.r * c.g;
    prefix[to + 7u] = prefix[from + 7u] + c.r * c.b;
    prefix[to + 8u] = prefix[from + 8u] + c.g * c.b;
  }
  const uint out_base = g_macro * kMacro;
  if (params.fixed_rate != 0u) {
    for (uint i = 0; i < g_colors; ++i) {
      const uint c = ColorAt(i);
      cand[CandAt(0u, i)] = uvec4(i, 1u, c, c);
    }
    const uint n = Merge(0u, g_colors, 3);
    for (uint k = 0; k < n; ++k) {
      const uvec4 c = cand[CandAt(0u, k)];
      blocks[out_base + k] = uvec4(out_base + c.x, c.y & 0xFFFFu, (c.z & 0xFFFFFFu) | (3u << 24), c.w);
    }
    block_count[g_macro] = n;
    return;
  }
  // The block tree: level b holds the merges at b bits of level b - 1's blocks.
  for (uint i = 0; i < g_colors; ++i) {
    const uint c = ColorAt(i);
    cand[CandAt(0u, i)] = uvec4(i, 1u, c, c);
  }
  counts[0] = Merge(0u, g_colors, 0);
  for (uint bits = 1u; bits < kLevels; ++bits) {
    for (uint k = 0; k < counts[bits - 1u]; ++k) {
      const uvec4 c = cand[CandAt(bits - 1u, k)];
      const Fit f = FitBlock(c.x, c.y & 0xFFFFu, int(bits), 0xFFFFFFFFFFFFFFFFul);
      cand[CandAt(bits, k)] = uvec4(c.x, c.y & 0xFFFFu, f.a, f.b);
    }
    counts[bits] = Merge(bits, counts[bits - 1u], int(bits));
  }
  // The cheapest cut, bottom-up: keep a node where it costs less than its children.
  for (uint k = 0; k < counts[0]; ++k) {
    cost[CandAt(0u, k)] = BlockCost(cand[CandAt(0u, k)].y & 0xFFFFu, 0u);
    cand[CandAt(0u, k)].z |= 1u << 24;
  }
  for (uint level = 1u; level < kLevels; ++level) {
    uint child = 0;
    for (uint k = 0; k < counts[level]; ++k) {
      const uvec4 c = cand[CandAt(level, k)];
      const uint stop = c.x + (c.y & 0xFFFFu);
      uint children = 0;
      for (; child < counts[level - 1u] && cand[CandAt(level - 1u, child)].x < stop; ++child) children += cost[CandAt(level - 1u, child)];
      const uint own = BlockCost(c.y & 0xFFFFu, level);
      cost[CandAt(level, k)] = own < children ? own : children;
      cand[CandAt(level, k)].z = (c.z & 0xFFFFFFu) | (own < children ? 1u << 24 : 0u);
    }
  }
  // Open nodes: the top level, and the children of open nodes not kept. Emitted: open and kept.
  for (uint k = 0; k < counts[kLevels - 1u]; ++k) cand[CandAt(kLevels - 1u, k)].z |= 1u << 25;
  for (uint step = 1u; step < kLevels; ++step) {
    const uint level = kLevels - step;
    uint parent = 0;
    for (uint k = 0; k < counts[level - 1u]; ++k) {
      const uint start = cand[CandAt(level - 1u, k)].x;
      // Every parent holds at least one child, so one step reaches the next parent.
      if (cand[CandAt(level, parent)].x + (cand[CandAt(level, parent)].y & 0xFFFFu) <= start) ++parent;
      const uint pz = cand[CandAt(level, parent)].z;
      if ((pz & (1u << 25)) != 0u && (pz & (1u << 24)) == 0u) cand[CandAt(level - 1u, k)].z |= 1u << 25;
    }
  }
  for (uint level = 0u; level < kLevels; ++level) cursor[level] = 0u;
  uint emitted = 0, pos = 0;
  while (pos < g_colors) {
    for (int level = int(kLevels) - 1; level >= 0; --level) {
      while (cursor[level] < counts[level] && cand[CandAt(uint(level), cursor[level])].x < pos) ++cursor[level];
      if (cursor[level] == counts[level]) continue;
      const uvec4 c = cand[CandAt(uint(level), cursor[level])];
      if (c.x == pos && (c.z & (3u << 24)) == (3u << 24)) {
        blocks[out_base + emitted++] = uvec4(out_base + c.x, c.y & 0xFFFFu, (c.z & 0xFFFFFFu) | (uint(level) << 24), c.w);
        pos += c.y & 0xFFFFu;
        break;
      }
    }
  }
  block_count[g_macro] = emitted;
}
