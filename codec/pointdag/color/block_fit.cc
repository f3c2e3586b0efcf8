#include "pointdag/color/block_fit.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <utility>

namespace pointdag {
namespace {

// Sums index: r g b, then rr gg bb rg rb gb; kPair[j][k] finds the product sum of channels j, k.
constexpr int kPair[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
constexpr int kAxisBits = 10;  // power iteration keeps the axis below 2^10 per component
// Two steps from the widest channel's column (itself one step from that channel): 8 steps cost a
// quarter of the fitter and gave the same sizes at equal PSNR-Y within the threshold search's noise.
constexpr int kPowerIterations = 2;
// A merge trial gives up once its first fit's error passes this many times the limit, refinement
// unseen: most failing trials end there, and merges refinement would have rescued from above 2x are
// few (lion 38 dB: 9 % of merges) and move sizes at equal PSNR-Y by less than the search's noise.
constexpr uint64_t kHopeless = 2;

uint8_t Clamp255(int64_t v) { return static_cast<uint8_t>(std::clamp<int64_t>(v, 0, 255)); }

// a / b rounded half up (floor((2a + b) / 2b)), clamped to 0..255, for several a over one b > 0.
// Without a 64-bit division (tens of cycles, a dozen per fit): the quotient from a double reciprocal
// is within 1 of the floor wherever the clamp does not decide, and one integer step corrects it.
// The floor of the clamped quotient x is that of x + 1, >= 0, truncated, less 1: within 1 as well, and
// cheaper than std::floor without SSE4.1. 257 (2b) stays below 2^62 for every caller.
class RoundDivider {
 public:
  explicit RoundDivider(int64_t b) : b_(b), inverse_(1.0 / double(2 * b)) {}
  uint8_t operator()(int64_t a) const {
    const int64_t num = 2 * a + b_, den = 2 * b_;
    int64_t q = static_cast<int64_t>(std::clamp(double(num) * inverse_, -1.0, 256.0) + 1.0) - 1;
    if (q < 256 && (q + 1) * den <= num) {
      ++q;
    } else if (q > -1 && q * den > num) {
      --q;
    }
    return Clamp255(q);
  }
  // The same for 0 <= a <= 255 b (a mean): the quotient is never clamped (0-bit fits, most of them).
  uint8_t Mean(int64_t a) const {
    const int64_t num = 2 * a + b_, den = 2 * b_;
    int64_t q = static_cast<int64_t>(double(num) * inverse_);
    q += (q + 1) * den <= num;
    q -= q * den > num;
    return static_cast<uint8_t>(q);
  }

 private:
  int64_t b_;
  double inverse_;
};

// sum over n colors of (c - a)^T M (c - a), M symmetric, from their sums s and product sums ss (Sums'
// order): sum_jk M_jk (ss_jk - a_j s_k - a_k s_j + n a_j a_k) = sum_jk M_jk ss_jk + a^T M (n a - 2 s),
// the same integer for 18 products instead of 45. Inlined, so that M's entries are constants.
__attribute__((always_inline)) inline int64_t ErrorAbout(const int64_t s[3], const int64_t ss[6], int64_t n, const int64_t a[3],
                                                         const int32_t (&metric)[3][3]) {
  int64_t sse = metric[0][0] * ss[0] + metric[1][1] * ss[1] + metric[2][2] * ss[2] +
                2 * (metric[0][1] * ss[3] + metric[0][2] * ss[4] + metric[1][2] * ss[5]);
  const int64_t t[3] = {n * a[0] - 2 * s[0], n * a[1] - 2 * s[1], n * a[2] - 2 * s[2]};
  for (int j = 0; j < 3; ++j) sse += a[j] * (metric[j][0] * t[0] + metric[j][1] * t[1] + metric[j][2] * t[2]);
  return sse;
}

// Arithmetic shift right until every component is below 2^kAxisBits in magnitude.
void Shrink(int64_t v[3]) {
  const uint64_t largest = static_cast<uint64_t>(std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])}));
  const int shift = std::max(0, static_cast<int>(std::bit_width(largest)) - kAxisBits);
  for (int k = 0; k < 3; ++k) v[k] >>= shift;
}

// ChooseWeight and Interpolate for one pair of endpoints, with the divisions done by multiplying: by
// 1 / (2 (B - A)^T Q (B - A)) with a nudge that keeps the floor exact (the numerator is below 2^34 and
// exact in a double, the denominator below 2^30, so a quotient that is not an integer is at least 2^-30
// from one, and the product's error, the quotient being below 16, is below 2^-47); Interpolate's once
// per weight, the palette as arrays so that the AVX2 loops gather from it. The palette's error may be
// taken in another metric (kChromaWeights): its terms are computed modulo 2^32, their sum d^T C d is
// exact (C is positive semidefinite, and its terms are below Q's).
struct Line {
  int32_t a[3];     // endpoint A
  int32_t q[3];     // Q (B - A)
  int32_t len2;     // (B - A)^T Q (B - A)
  int32_t m;        // 2^bits - 1
  double inverse;   // 1 / (2 len2), 0 if len2 is 0
  int32_t twice_qp[3][16];  // 2 M p for p = Interpolate(e, w), per w, M the palette's metric
  uint32_t norm[16];        // p^T M p

  // (c - A)^T Q (B - A)
  int32_t Dot(int32_t r, int32_t g, int32_t b) const { return (r - a[0]) * q[0] + (g - a[1]) * q[1] + (b - a[2]) * q[2]; }
  // ChooseWeight for 0 <= dot <= len2; at the ends the quotient is 1/2 and m + 1/2 (0 if len2 is 0),
  // so that clamping dot gives ChooseWeight's 0 and m without a branch.
  int32_t Round(int32_t dot) const { return static_cast<int32_t>((double(dot) * (2.0 * m) + len2) * inverse + 0x1p-38); }
  int32_t Weight(int32_t dot) const { return dot <= 0 ? 0 : dot >= len2 ? m : Round(dot); }
  // BlockError(c, Interpolate(e, w)) from c's norm c^T Q c: c^T Q c - 2 c^T Q p + p^T Q p, the same
  // integer for three products instead of twelve (every term is below 2^31).
  uint32_t Error(int32_t r, int32_t g, int32_t b, uint32_t c_norm, int32_t w) const {
    return c_norm + norm[w] - static_cast<uint32_t>(r * twice_qp[0][w] + g * twice_qp[1][w] + b * twice_qp[2][w]);
  }
};

template <int kBits>
Line MakeLine(const Endpoints& e, const int32_t (&metric)[3][3] = kErrorWeights) {
  constexpr uint32_t kM = (1u << kBits) - 1;
  Line line;  // palette entries past m stay unset: no weight reaches them
  const std::array<int32_t, 3> q = WeightedAxis(e);
  const int32_t a[3] = {e.a.r, e.a.g, e.a.b};
  for (int k = 0; k < 3; ++k) line.a[k] = a[k], line.q[k] = q[k];
  line.len2 = (e.b.r - e.a.r) * q[0] + (e.b.g - e.a.g) * q[1] + (e.b.b - e.a.b) * q[2];
  line.m = static_cast<int32_t>(kM);
  line.inverse = line.len2 ? 1.0 / (2.0 * line.len2) : 0.0;
  const auto mix = [](uint32_t x, uint32_t y, uint32_t w) { return static_cast<int32_t>((x * (kM - w) + y * w + kM / 2) / kM); };
  for (uint32_t w = 0; w <= kM; ++w) {
    const int32_t p[3] = {mix(e.a.r, e.b.r, w), mix(e.a.g, e.b.g, w), mix(e.a.b, e.b.b, w)};
    line.norm[w] = 0;
    for (int j = 0; j < 3; ++j) {
      const int32_t qp = metric[j][0] * p[0] + metric[j][1] * p[1] + metric[j][2] * p[2];
      line.twice_qp[j][w] = 2 * qp;
      line.norm[w] += static_cast<uint32_t>(p[j] * qp);
    }
  }
  return line;
}

// A run of colors from `begin`: as Rgb8 for the scalar loops, as padded planes for the AVX2 ones.
struct Run {
  const Rgb8* colors;
  const int32_t* r;  // null without AVX2
  const int32_t* g;
  const int32_t* b;
  const uint32_t* norms;
  uint32_t length;
};

// The first fit's error and what the least-squares refinement needs of its weights.
struct Weighed {
  uint64_t sse = 0;
  int32_t w = 0, ww = 0, wc[3] = {0, 0, 0};
  bool hopeless = false;  // the error of the colors before the last passed the limit: the rest unseen
};

// Two loops per step, one result: the scalar loops go color by color with the early exits (the first
// fit gives up once the error of the colors before the last passes `hopeless`; the second stops at the
// first color whose error passes `stop`); the AVX2 ones weigh 8 colors at a time (one vector; fits
// average ~15 colors), masked past the run's end, and resolve those exits inside the chunk. The scalar
// loops are the fallback because GCC's SSE2 code for the chunks is 14 % slower than they are.
Weighed WeighScalar(const Run& run, const Line& line, uint64_t hopeless) {
  Weighed out;
  for (uint32_t i = 0; i < run.length; ++i) {
    if (out.sse > hopeless) return {.hopeless = true};
    const Rgb8 c = run.colors[i];
    const int32_t w = line.Weight(line.Dot(c.r, c.g, c.b));
    out.sse += line.Error(c.r, c.g, c.b, run.norms[i], w);
    out.w += w, out.ww += w * w;
    out.wc[0] += w * c.r, out.wc[1] += w * c.g, out.wc[2] += w * c.b;
  }
  return out;
}

uint64_t ErrorScalar(const Run& run, const Line& line, uint64_t stop) {
  uint64_t sse = 0;
  for (uint32_t i = 0; i < run.length && sse <= stop; ++i) {
    const Rgb8 c = run.colors[i];
    sse += line.Error(c.r, c.g, c.b, run.norms[i], line.Weight(line.Dot(c.r, c.g, c.b)));
  }
  return sse;
}

// The AVX2 copies are compiled for x86-64 only; elsewhere they are plain code that UseAvx2() never picks.
#if defined(__x86_64__)
#define POINTDAG_AVX2 __attribute__((target("avx2")))
#else
#define POINTDAG_AVX2
#endif

constexpr uint32_t kChunk = 8;  // a fixed count: GCC's -O2 vectorizes no loop that needs an epilogue
static_assert(kChunk * 255 * 255 * 3072 < (uint64_t{1} << 32));  // a chunk's error fits 32 bits

// Errors e[i] of colors [begin, begin + n) (0 past n) with the sums of one chunk.
struct ChunkSums {
  uint32_t sse;
  int32_t w, ww, wc[3];
};
POINTDAG_AVX2 __attribute__((always_inline)) inline ChunkSums WeighChunk(const Run& run, uint32_t begin, uint32_t n, const Line& line, uint32_t* __restrict e) {
  const int32_t* __restrict r = run.r + begin;
  const int32_t* __restrict g = run.g + begin;
  const int32_t* __restrict b = run.b + begin;
  const uint32_t* __restrict norms = run.norms + begin;
  ChunkSums out{0, 0, 0, {0, 0, 0}};
  for (uint32_t i = 0; i < kChunk; ++i) {
    const int32_t weight = line.Round(std::min(std::max(line.Dot(r[i], g[i], b[i]), 0), line.len2));
    const uint32_t error = line.Error(r[i], g[i], b[i], norms[i], weight);
    const int32_t wi = i < n ? weight : 0;
    e[i] = i < n ? error : 0;
    out.sse += e[i];
    out.w += wi, out.ww += wi * wi;
    out.wc[0] += wi * r[i], out.wc[1] += wi * g[i], out.wc[2] += wi * b[i];
  }
  return out;
}

POINTDAG_AVX2 Weighed WeighAvx2(const Run& run, const Line& line, uint64_t hopeless) {
  Weighed out;
  uint32_t e[kChunk];
  for (uint32_t begin = 0; begin < run.length; begin += kChunk) {
    const uint32_t n = std::min(kChunk, run.length - begin);
    const ChunkSums chunk = WeighChunk(run, begin, n, line, e);
    out.sse += chunk.sse;
    out.w += chunk.w, out.ww += chunk.ww;
    for (int k = 0; k < 3; ++k) out.wc[k] += chunk.wc[k];
    const bool last = begin + n == run.length;
    if ((last ? out.sse - e[n - 1] : out.sse) > hopeless) return {.hopeless = true};
  }
  return out;
}

POINTDAG_AVX2 uint64_t ErrorAvx2(const Run& run, const Line& line, uint64_t stop) {
  uint64_t sse = 0;
  uint32_t e[kChunk];
  for (uint32_t begin = 0; begin < run.length && sse <= stop; begin += kChunk) {
    const uint32_t n = std::min(kChunk, run.length - begin);
    const uint32_t chunk = WeighChunk(run, begin, n, line, e).sse;
    if (sse + chunk <= stop) {
      sse += chunk;
    } else {
      for (uint32_t i = 0; i < n && sse <= stop; ++i) sse += e[i];
    }
  }
  return sse;
}

// The lowest and highest projection c^T qa of a run's colors.
std::pair<int32_t, int32_t> ExtentScalar(const Run& run, const int32_t qa[3]) {
  int32_t lowest = INT32_MAX, highest = INT32_MIN;
  for (uint32_t i = 0; i < run.length; ++i) {
    const int32_t p = run.colors[i].r * qa[0] + run.colors[i].g * qa[1] + run.colors[i].b * qa[2];
    lowest = std::min(lowest, p), highest = std::max(highest, p);
  }
  return {lowest, highest};
}

// Per lane over the whole chunks, the rest color by color: GCC 12 made the masked chunks of one
// accumulator a branch per color, unvectorized (lion: 4 % of an encode's instructions).
POINTDAG_AVX2 std::pair<int32_t, int32_t> ExtentAvx2(const Run& run, const int32_t qa[3]) {
  const int32_t* __restrict r = run.r;
  const int32_t* __restrict g = run.g;
  const int32_t* __restrict b = run.b;
  const int32_t q0 = qa[0], q1 = qa[1], q2 = qa[2];
  int32_t lowest[kChunk], highest[kChunk];
  std::fill_n(lowest, kChunk, INT32_MAX);
  std::fill_n(highest, kChunk, INT32_MIN);
  const uint32_t whole = run.length - run.length % kChunk;
  for (uint32_t begin = 0; begin < whole; begin += kChunk) {
    for (uint32_t i = 0; i < kChunk; ++i) {
      const int32_t p = r[begin + i] * q0 + g[begin + i] * q1 + b[begin + i] * q2;
      lowest[i] = std::min(lowest[i], p), highest[i] = std::max(highest[i], p);
    }
  }
  for (uint32_t i = whole; i < run.length; ++i) {
    const int32_t p = r[i] * q0 + g[i] * q1 + b[i] * q2;
    lowest[0] = std::min(lowest[0], p), highest[0] = std::max(highest[0], p);
  }
  return {*std::min_element(lowest, lowest + kChunk), *std::max_element(highest, highest + kChunk)};
}

// Weights and error for `ends`, then endpoints refined by least squares for those weights
// (with u = m - w, t = w: minimise sum(u A + t B - m c)^2 per channel); the better fit wins.
// The least-squares sums come from sum(w), sum(w^2) and sum(w c) (below 2^26): with n colors,
// sum(u t) = m sum(w) - sum(w^2), sum(u^2) = m^2 n - 2 m sum(w) + sum(w^2), sum(u c) = m sum(c) - sum(w c).
template <int kBits>
BlockFit FitWeights(const Run& run, const int64_t sums[3], const Endpoints& ends, uint64_t give_up_above) {
  constexpr int64_t m = (1 << kBits) - 1;
  const bool avx2 = run.r != nullptr;
  const Line first = MakeLine<kBits>(ends);
  const uint64_t hopeless = give_up_above <= UINT64_MAX / kHopeless ? kHopeless * give_up_above : UINT64_MAX;
  const Weighed weighed = avx2 ? WeighAvx2(run, first, hopeless) : WeighScalar(run, first, hopeless);
  if (weighed.hopeless) return {ends, give_up_above + 1};
  BlockFit best{ends, weighed.sse};
  const int64_t s11 = weighed.ww, s01 = m * weighed.w - weighed.ww, s00 = m * m * int64_t{run.length} - 2 * m * weighed.w + weighed.ww;
  int64_t r0[3], r1[3];
  for (int k = 0; k < 3; ++k) r1[k] = weighed.wc[k], r0[k] = m * sums[k] - weighed.wc[k];
  const int64_t det = s00 * s11 - s01 * s01;
  if (det <= 0 || best.sse == 0) return best;
  uint8_t a[3], b[3];
  const RoundDivider divide(det);
  for (int k = 0; k < 3; ++k) {
    a[k] = divide(m * (s11 * r0[k] - s01 * r1[k]));
    b[k] = divide(m * (s00 * r1[k] - s01 * r0[k]));
  }
  const Endpoints refined{{a[0], a[1], a[2]}, {b[0], b[1], b[2]}};
  if (refined == best.ends) return best;
  const Line second = MakeLine<kBits>(refined);
  const uint64_t stop = std::min(best.sse, give_up_above);
  const uint64_t sse = avx2 ? ErrorAvx2(run, second, stop) : ErrorScalar(run, second, stop);
  if (sse < best.sse) best = {refined, sse};
  return best;
}

// BlockFitter::ChromaError of a run whose norms are c^T C c (C = kChromaWeights), for wider blocks:
// ChooseWeight by the fitter's projection, the palette's error in C, stopping past `stop`.
template <int kBits>
uint64_t ChromaOfRun(const Run& run, const Endpoints& ends, uint64_t stop) {
  const Line line = MakeLine<kBits>(ends, kChromaWeights);
  return run.r ? ErrorAvx2(run, line, stop) : ErrorScalar(run, line, stop);
}

}  // namespace

bool BlockFitter::UseAvx2() {
#if defined(__x86_64__)
  static const bool use = __builtin_cpu_supports("avx2") && std::getenv("POINTDAG_NO_AVX2") == nullptr;
  return use;
#else
  return false;
#endif
}

BlockFitter::BlockFitter(std::span<const Rgb8> colors)
    : colors_(colors),
      prefix_(colors.size() + 1),
      norms_(colors.size() + kChunk),
      chroma_norms_(colors.size() + kChunk),
      avx2_(UseAvx2()) {
  prefix_[0].fill(0);
  if (avx2_) {
    for (auto& plane : planes_) plane.resize(colors.size() + kChunk);
  }
  // c^T M c from c's products (the sums' order), modulo 2^32: BlockError against black for Q.
  const auto norm = [](const std::array<uint32_t, 9>& p, const int32_t (&m)[3][3]) {
    return static_cast<uint32_t>(m[0][0] * p[3] + m[1][1] * p[4] + m[2][2] * p[5] + 2 * (m[0][1] * p[6] + m[0][2] * p[7] + m[1][2] * p[8]));
  };
  std::array<uint32_t, 9> sums{};
  for (size_t i = 0; i < colors.size(); ++i) {
    const uint32_t r = colors[i].r, g = colors[i].g, b = colors[i].b;
    const std::array<uint32_t, 9> add = {r, g, b, r * r, g * g, b * b, r * g, r * b, g * b};
    for (int k = 0; k < 9; ++k) sums[k] += add[k];
    prefix_[i + 1] = sums;
    norms_[i] = norm(add, kErrorWeights);
    chroma_norms_[i] = norm(add, kChromaWeights);
    if (avx2_) planes_[0][i] = r, planes_[1][i] = g, planes_[2][i] = b;
  }
}

inline BlockFitter::Sums BlockFitter::RangeSums(uint32_t begin, uint32_t end) const {
  Sums out;
  for (int k = 0; k < 3; ++k) out.s[k] = int64_t{prefix_[end][k]} - prefix_[begin][k];
  for (int k = 0; k < 6; ++k) out.ss[k] = int64_t{prefix_[end][3 + k]} - prefix_[begin][3 + k];
  return out;
}

BlockFit BlockFitter::Fit(uint32_t begin, uint32_t length, int bits, uint64_t give_up_above) const {
  // A leaf (the tree fits every color alone at every width): the mean path's result, without the sums.
  if (length == 1) return {{colors_[begin], colors_[begin]}, 0, 0};
  const int64_t n = length;
  const Sums sums = RangeSums(begin, begin + length);
  // One color for the whole block (0 bits, or all colors alike): the mean, whose error follows from the sums alone.
  const auto mean = [&]() -> BlockFit {
    const RoundDivider divide(n);
    const Rgb8 c{divide.Mean(sums.s[0]), divide.Mean(sums.s[1]), divide.Mean(sums.s[2])};
    const int64_t a[3] = {c.r, c.g, c.b};
    return {{c, c}, static_cast<uint64_t>(ErrorAbout(sums.s, sums.ss, n, a, kErrorWeights)),
            static_cast<uint64_t>(ErrorAbout(sums.s, sums.ss, n, a, kChromaWeights))};
  };
  if (bits == 0) return mean();
  // Covariance scaled by n^2: M[j][k] = n * sum(c_j c_k) - sum(c_j) sum(c_k).
  int64_t cov[3][3];
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 3; ++k) cov[j][k] = n * sums.ss[kPair[j][k]] - sums.s[j] * sums.s[k];
  }
  const int widest = cov[0][0] >= cov[1][1] ? (cov[0][0] >= cov[2][2] ? 0 : 2) : (cov[1][1] >= cov[2][2] ? 1 : 2);
  if (cov[widest][widest] == 0) return mean();
  // Principal axis in BlockError's metric (that of the colors' covariance with Q: v <- C Q v, the
  // RGB image of the principal axis of L^T C L, Q = L L^T) by power iteration, starting from the
  // widest channel's column. Q v is shrunk too, so that C (Q v) stays below 2^57.
  int64_t axis[3] = {cov[0][widest], cov[1][widest], cov[2][widest]};
  Shrink(axis);
  int64_t qa[3];
  const auto weigh = [&] {
    for (int j = 0; j < 3; ++j) qa[j] = kErrorWeights[j][0] * axis[0] + kErrorWeights[j][1] * axis[1] + kErrorWeights[j][2] * axis[2];
  };
  for (int iter = 0; iter < kPowerIterations; ++iter) {
    weigh();
    Shrink(qa);
    int64_t next[3];
    for (int j = 0; j < 3; ++j) next[j] = cov[j][0] * qa[0] + cov[j][1] * qa[1] + cov[j][2] * qa[2];
    if (next[0] == 0 && next[1] == 0 && next[2] == 0) break;
    Shrink(next);
    if (next[0] == axis[0] && next[1] == axis[1] && next[2] == axis[2]) break;  // a fixed point: the rest would repeat it
    std::copy(next, next + 3, axis);
  }
  // Extent of the colors along the axis (projections (n c - s)^T Q axis = n c^T Q axis - s^T Q axis, the
  // first term's c^T Q axis below 2^30), endpoints at both ends.
  weigh();
  const auto plane = [&](int k) { return avx2_ ? planes_[k].data() + begin : nullptr; };
  const Run run{colors_.data() + begin, plane(0), plane(1), plane(2), norms_.data() + begin, length};
  const int32_t qa32[3] = {static_cast<int32_t>(qa[0]), static_cast<int32_t>(qa[1]), static_cast<int32_t>(qa[2])};
  const auto [lowest, highest] = avx2_ ? ExtentAvx2(run, qa32) : ExtentScalar(run, qa32);
  const int64_t centre = sums.s[0] * qa[0] + sums.s[1] * qa[1] + sums.s[2] * qa[2];
  const int64_t lo = std::min<int64_t>(0, n * lowest - centre), hi = std::max<int64_t>(0, n * highest - centre);
  const int64_t axis2 = axis[0] * qa[0] + axis[1] * qa[1] + axis[2] * qa[2];
  const RoundDivider divide(n * axis2);
  const auto along = [&](int64_t t, int k) { return divide(sums.s[k] * axis2 + t * axis[k]); };
  const Endpoints ends{{along(lo, 0), along(lo, 1), along(lo, 2)}, {along(hi, 0), along(hi, 1), along(hi, 2)}};

  switch (bits) {
    case 1: return FitWeights<1>(run, sums.s, ends, give_up_above);
    case 2: return FitWeights<2>(run, sums.s, ends, give_up_above);
    case 3: return FitWeights<3>(run, sums.s, ends, give_up_above);
    default: return FitWeights<4>(run, sums.s, ends, give_up_above);
  }
}

uint64_t BlockFitter::ChromaError(uint32_t begin, uint32_t length, int bits, const Endpoints& ends, uint64_t give_up_above) const {
  if (length == 1 && ends.a == ends.b && ends.a == colors_[begin]) return 0;  // a leaf as fitted: exact
  if (bits == 0 || ends.a == ends.b) {
    const Sums sums = RangeSums(begin, begin + length);
    const int64_t a[3] = {ends.a.r, ends.a.g, ends.a.b};
    return static_cast<uint64_t>(ErrorAbout(sums.s, sums.ss, length, a, kChromaWeights));
  }
  const auto plane = [&](int k) { return avx2_ ? planes_[k].data() + begin : nullptr; };
  const Run run{colors_.data() + begin, plane(0), plane(1), plane(2), chroma_norms_.data() + begin, length};
  switch (bits) {
    case 1: return ChromaOfRun<1>(run, ends, give_up_above);
    case 2: return ChromaOfRun<2>(run, ends, give_up_above);
    case 3: return ChromaOfRun<3>(run, ends, give_up_above);
    default: return ChromaOfRun<4>(run, ends, give_up_above);
  }
}

}  // namespace pointdag
