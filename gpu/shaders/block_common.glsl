// Shared by the block encoder kernels (block_*.comp): their buffers, parameters, and the block fit.
// The same integer steps in the same order as codec/pointdag/color/block_fit.cc (BlockFitter::Fit,
// FitWeights) and block_codec.cc (MergePasses, VariableRateMacroBlock), so that the blocks, and the
// .pdag bytes, come out identical: change one, change the other (gpu_test compares them).
//
// Every invocation stays far below 65535 loop iterations in all: Mesa's llvmpipe (lavapipe) stops
// any loop once a shader invocation has run that many (LP_MAX_TGSI_LOOP_ITERATIONS), silently. So a
// macro block is not encoded by one invocation: fits run one per invocation, and the per-macro-block
// steps (prefix sums, one merge pass, one level of the cut) walk at most 2 x 16384 entries.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(push_constant) uniform Params {
  uint count;         // colors in all
  uint macros;        // macro blocks
  uint level;         // level of the block tree (0..4) a kernel works on
  uint bits;          // bits per weight of the fits
  uint threshold_lo;  // Threshold::scaled, low and high words
  uint threshold_hi;
  uint fixed_rate;    // 1: IIA, 3 bits everywhere, one level; 0: IIB variable rate
  uint slot;          // merge pass within a submission (block_merge counts merges per slot)
} params;

const uint kMacro = 16384u;
const uint kLevels = 5u;  // 0..4 bits per weight
const uint kKeep = 1u << 24, kOpen = 1u << 25;

layout(std430, binding = 0) readonly buffer Colors { uint colors[]; };  // r | g << 8 | b << 16
layout(std430, binding = 1) buffer Prefix { uint prefix[]; };           // per macro: (kMacro + 1) x 9 sums
// Candidates, per macro and level, kMacro each: x start, y length | failed_with << 16,
// z endpoint A | kKeep | kOpen, w endpoint B.
layout(std430, binding = 2) buffer Levels { uvec4 cand[]; };
// Per macro, kMacro each: during merging, x = 1 + (error >> 32) where candidate k merges with k + 1
// (y, z its endpoints, w the error's low word); during the cut, at a block's start: x = 1 + level,
// y = its index at that level.
layout(std430, binding = 3) buffer Pairs { uvec4 pair[]; };
// Parallel to cand: a candidate's error (its fit's sse; variable rate: WeighedError) while the tree is built; the cut replaces it
// with the cheapest cost of coding it.
layout(std430, binding = 4) buffer Costs { uint64_t cost[]; };
layout(std430, binding = 5) buffer Counts { uint counts[]; };  // per macro and level
layout(std430, binding = 6) buffer Blocks { uvec4 blocks[]; };  // per macro: kMacro, then its count at kMacro * macros + m
layout(std430, binding = 7) buffer Merges { uint merges[]; };   // per slot: macro blocks that merged something

uint MacroColors(uint m) { return min(kMacro, params.count - m * kMacro); }
uint CandAt(uint m, uint level, uint k) { return (m * kLevels + level) * kMacro + k; }
uint CountAt(uint m, uint level) { return m * kLevels + level; }
uint Length(uvec4 c) { return c.y & 0xFFFFu; }
uint FailedWith(uvec4 c) { return c.y >> 16; }

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

// Threshold::scaled (block_codec.cc).
uint64_t Scaled() { return uint64_t(params.threshold_lo) | (uint64_t(params.threshold_hi) << 32); }
uint64_t MaxSse(uint length) { return uint64_t(length) * Scaled(); }

// block_codec.cc's RateTenths: a block's bits for the variable-rate tree and cut, in tenths of a bit.
const uint kHeaderTenths = 1000u, kSecondEndTenths = 1000u;
const uint64_t kTenthsPerSse = 20ul;
uint WeightTenths(uint bits) { return bits == 0u ? 0u : bits == 1u ? 6u : bits == 2u ? 10u : bits == 3u ? 17u : 25u; }
uint64_t RateTenths(uint length, uint bits) {
  return uint64_t(kHeaderTenths + (bits != 0u ? kSecondEndTenths : 0u)) + uint64_t(length) * uint64_t(WeightTenths(bits));
}

void Shrink(inout i64vec3 v) {
  const int64_t largest = max(max(Abs64(v.x), Abs64(v.y)), Abs64(v.z));
  const int shift = max(0, BitWidth(uint64_t(largest)) - 10);
  v = v >> shift;
}

// kErrorWeights and BlockError (block_fit.h): the luma-weighted error in 1/1024ths, by rows.
const ivec3 kQ0 = ivec3(274, 373, 6), kQ1 = ivec3(373, 1753, 71), kQ2 = ivec3(6, 71, 145);

// ChooseWeight (block_fit.h): projection in BlockError's metric; q = Q (B - A), len2 = (B - A)^T q.
uint WeightOf(ivec3 c, ivec3 a, ivec3 q, int len2, int m) {
  const int dot_ = (c.x - a.x) * q.x + (c.y - a.y) * q.y + (c.z - a.z) * q.z;
  if (dot_ <= 0) return 0u;
  if (dot_ >= len2) return uint(m);
  return uint((int64_t(2) * int64_t(m) * int64_t(dot_) + int64_t(len2)) / (int64_t(2) * int64_t(len2)));
}

i64vec3 WeightedAxis64(i64vec3 d) {
  return i64vec3(kQ0.x * d.x + kQ0.y * d.y + kQ0.z * d.z, kQ1.x * d.x + kQ1.y * d.y + kQ1.z * d.z, kQ2.x * d.x + kQ2.y * d.y + kQ2.z * d.z);
}

ivec3 WeightedAxis(ivec3 d) {
  return ivec3(kQ0.x * d.x + kQ0.y * d.y + kQ0.z * d.z, kQ1.x * d.x + kQ1.y * d.y + kQ1.z * d.z, kQ2.x * d.x + kQ2.y * d.y + kQ2.z * d.z);
}

uint ErrorOf(ivec3 c, ivec3 a, ivec3 b, uint w, uint m) {
  const uvec3 r = (uvec3(a) * (m - w) + uvec3(b) * w + m / 2u) / m;
  const ivec3 e = c - ivec3(r);
  const ivec3 q = ivec3(kQ0.x * e.x + kQ0.y * e.y + kQ0.z * e.z, kQ1.x * e.x + kQ1.y * e.y + kQ1.z * e.z,
                        kQ2.x * e.x + kQ2.y * e.y + kQ2.z * e.z);
  return uint(e.x * q.x + e.y * q.y + e.z * q.z);
}

struct Fit {
  uint a, b;
  uint64_t sse;
};

// BlockFitter::Fit and FitWeights for colors [begin, begin + length) of macro block m. Written with
// vector components, not indexed arrays: lavapipe (Mesa 22.3) miscompiles dynamically indexed
// private arrays. At most 3 x length + 2 loop iterations.
Fit FitBlock(uint m, uint begin, uint length, int bits, uint64_t give_up_above) {
  const int64_t n = int64_t(length);
  const uint base = m * (kMacro + 1u) * 9u;
  const uint lo_at = base + begin * 9u, hi_at = base + (begin + length) * 9u;
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
    // sum_jk Q_jk (ss_jk - a_j s_k - a_k s_j + n a_j a_k): squares, then products rg rb gb (twice each).
    const i64vec3 e = sq - 2 * a * s + n * a * a;
    const i64vec3 p = pr - i64vec3(a.x * s.y + a.y * s.x, a.x * s.z + a.z * s.x, a.y * s.z + a.z * s.y) +
                      n * i64vec3(a.x * a.y, a.x * a.z, a.y * a.z);
    const int64_t sse = int64_t(kQ0.x) * e.x + int64_t(kQ1.y) * e.y + int64_t(kQ2.z) * e.z +
                        2 * (int64_t(kQ0.y) * p.x + int64_t(kQ0.z) * p.y + int64_t(kQ1.z) * p.z);
    const uint c = Pack(Clamp255(a.x), Clamp255(a.y), Clamp255(a.z));
    return Fit(c, c, uint64_t(sse));
  }
  // Principal axis in BlockError's metric: v <- C (Q v), Q v shrunk too.
  i64vec3 axis = widest == 0 ? c0 : (widest == 1 ? c1 : c2);
  Shrink(axis);
  for (int iter = 0; iter < 2; ++iter) {  // kPowerIterations
    i64vec3 qa = WeightedAxis64(axis);
    Shrink(qa);
    // cov * qa, cov symmetric: row j = column j. (Not dot(): GLSL's dot() is floating point.)
    i64vec3 next = i64vec3(c0.x * qa.x + c0.y * qa.y + c0.z * qa.z, c1.x * qa.x + c1.y * qa.y + c1.z * qa.z,
                          c2.x * qa.x + c2.y * qa.y + c2.z * qa.z);
    if (next.x == 0 && next.y == 0 && next.z == 0) break;
    Shrink(next);
    axis = next;
  }
  const i64vec3 qa = WeightedAxis64(axis);
  const uint first = m * kMacro + begin;
  int64_t lo = 0, hi = 0;
  for (uint i = 0; i < length; ++i) {
    const i64vec3 d = n * i64vec3(Unpack(colors[first + i])) - s;
    const int64_t t = d.x * qa.x + d.y * qa.y + d.z * qa.z;
    lo = min(lo, t);
    hi = max(hi, t);
  }
  const int64_t axis2 = axis.x * qa.x + axis.y * qa.y + axis.z * qa.z;
  const int64_t den = n * axis2;
  Fit best = Fit(Pack(Clamp255(RoundDiv(s.x * axis2 + lo * axis.x, den)), Clamp255(RoundDiv(s.y * axis2 + lo * axis.y, den)),
                      Clamp255(RoundDiv(s.z * axis2 + lo * axis.z, den))),
                 Pack(Clamp255(RoundDiv(s.x * axis2 + hi * axis.x, den)), Clamp255(RoundDiv(s.y * axis2 + hi * axis.y, den)),
                      Clamp255(RoundDiv(s.z * axis2 + hi * axis.z, den))),
                 0ul);

  const int mx = (1 << bits) - 1;
  const ivec3 a = Unpack(best.a), b = Unpack(best.b), d = b - a, q = WeightedAxis(d);
  const int len2 = d.x * q.x + d.y * q.y + d.z * q.z;
  int64_t s00 = 0, s01 = 0, s11 = 0;
  i64vec3 r0 = i64vec3(0), r1 = i64vec3(0);
  // kHopeless = 2: give up once the unrefined error passes twice the limit.
  const uint64_t hopeless = give_up_above <= (0xFFFFFFFFFFFFFFFFul >> 1) ? 2ul * give_up_above : 0xFFFFFFFFFFFFFFFFul;
  for (uint i = 0; i < length; ++i) {
    if (best.sse > hopeless) return Fit(best.a, best.b, give_up_above + 1ul);
    const ivec3 c = Unpack(colors[first + i]);
    const uint w = WeightOf(c, a, q, len2, mx);
    best.sse += uint64_t(ErrorOf(c, a, b, w, uint(mx)));
    const int64_t u = int64_t(mx) - int64_t(w), t = int64_t(w);
    s00 += u * u;
    s01 += u * t;
    s11 += t * t;
    r0 += u * i64vec3(c);
    r1 += t * i64vec3(c);
  }
  const int64_t det = s00 * s11 - s01 * s01;
  if (det <= 0 || best.sse == 0) return best;
  const i64vec3 na = int64_t(mx) * (s11 * r0 - s01 * r1), nb = int64_t(mx) * (s00 * r1 - s01 * r0);
  const uint refined_a = Pack(Clamp255(RoundDiv(na.x, det)), Clamp255(RoundDiv(na.y, det)), Clamp255(RoundDiv(na.z, det)));
  const uint refined_b = Pack(Clamp255(RoundDiv(nb.x, det)), Clamp255(RoundDiv(nb.y, det)), Clamp255(RoundDiv(nb.z, det)));
  if (refined_a == best.a && refined_b == best.b) return best;
  const ivec3 a2 = Unpack(refined_a), b2 = Unpack(refined_b), d2 = b2 - a2, q2 = WeightedAxis(d2);
  const int len2b = d2.x * q2.x + d2.y * q2.y + d2.z * q2.z;
  const uint64_t stop = min(best.sse, give_up_above);
  uint64_t sse = 0;
  for (uint i = 0; i < length && sse <= stop; ++i) {
    const ivec3 c = Unpack(colors[first + i]);
    sse += uint64_t(ErrorOf(c, a2, b2, WeightOf(c, a2, q2, len2b, mx), uint(mx)));
  }
  if (sse < best.sse) best = Fit(refined_a, refined_b, sse);
  return best;
}

// block_codec.cc's WeighedError: what the variable-rate tree and cut weigh a fit by, its BlockError
// plus kChromaTimes x its chroma part (kChromaWeights, of the block rebuilt with projected weights).
// Two colors an iteration: with FitBlock's 3 x length + 2, under 65535 for a whole macro block.
const ivec3 kC0 = ivec3(135, -94, -41), kC1 = ivec3(-94, 182, -88), kC2 = ivec3(-41, -88, 129);
const uint64_t kChromaTimes = 4ul;

int ChromaOf(ivec3 c, ivec3 a, ivec3 b, ivec3 q, int len2, int mx) {
  const uint w = mx == 0 ? 0u : WeightOf(c, a, q, len2, mx);
  const ivec3 e = c - (mx == 0 ? a : ivec3((uvec3(a) * (uint(mx) - w) + uvec3(b) * w + uint(mx) / 2u) / uint(mx)));
  return e.x * (kC0.x * e.x + kC0.y * e.y + kC0.z * e.z) + e.y * (kC1.x * e.x + kC1.y * e.y + kC1.z * e.z) +
         e.z * (kC2.x * e.x + kC2.y * e.y + kC2.z * e.z);
}

uint64_t WeighedError(uint m, uint begin, uint length, int bits, Fit f) {
  const int mx = (1 << bits) - 1;
  const ivec3 a = Unpack(f.a), b = Unpack(f.b), d = b - a, q = WeightedAxis(d);
  const int len2 = d.x * q.x + d.y * q.y + d.z * q.z;
  const uint first = m * kMacro + begin;
  int64_t e = 0;
  uint i = 0u;
  for (; i + 1u < length; i += 2u) {
    e += int64_t(ChromaOf(Unpack(colors[first + i]), a, b, q, len2, mx)) + int64_t(ChromaOf(Unpack(colors[first + i + 1u]), a, b, q, len2, mx));
  }
  if (i < length) e += int64_t(ChromaOf(Unpack(colors[first + i]), a, b, q, len2, mx));
  return f.sse + kChromaTimes * uint64_t(max(e, int64_t(0)));
}
