#include "pointdag/color/block_fit.h"

#include <algorithm>
#include <bit>
#include <cmath>

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
// 257 (2b) stays below 2^62 for every caller.
class RoundDivider {
 public:
  explicit RoundDivider(int64_t b) : b_(b), inverse_(1.0 / double(2 * b)) {}
  uint8_t operator()(int64_t a) const {
    const int64_t num = 2 * a + b_, den = 2 * b_;
    int64_t q = static_cast<int64_t>(std::clamp(std::floor(double(num) * inverse_), -1.0, 256.0));
    if (q < 256 && (q + 1) * den <= num) {
      ++q;
    } else if (q > -1 && q * den > num) {
      --q;
    }
    return Clamp255(q);
  }

 private:
  int64_t b_;
  double inverse_;
};

// Arithmetic shift right until every component is below 2^kAxisBits in magnitude.
void Shrink(int64_t v[3]) {
  const uint64_t largest = static_cast<uint64_t>(std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])}));
  const int shift = std::max(0, static_cast<int>(std::bit_width(largest)) - kAxisBits);
  for (int k = 0; k < 3; ++k) v[k] >>= shift;
}

// ChooseWeight and Interpolate for one pair of endpoints, with the divisions done by multiplying (and
// Interpolate's by a table of the 2^bits colors):
// by a compile-time m, and by 1 / (2 (B - A)^T Q (B - A)) with a nudge that keeps the floor exact (the
// numerator is below 2^34 and the denominator below 2^30, so a quotient that is not an integer is
// at least 2^-30 from one, and the product's error, the quotient being below 16, is below 2^-47).
template <int kBits>
class Rebuilder {
 public:
  static constexpr int32_t kM = (1 << kBits) - 1;

  explicit Rebuilder(const Endpoints& e) : e_(e), q_(WeightedAxis(e)) {
    len2_ = (e.b.r - e.a.r) * q_[0] + (e.b.g - e.a.g) * q_[1] + (e.b.b - e.a.b) * q_[2];
    inverse_ = len2_ ? 1.0 / (2.0 * len2_) : 0.0;
    const auto mix = [](uint32_t a, uint32_t b, uint32_t w) { return static_cast<int32_t>((a * (kM - w) + b * w + kM / 2) / kM); };
    for (uint32_t w = 0; w <= kM; ++w) {
      const int32_t p[3] = {mix(e.a.r, e.b.r, w), mix(e.a.g, e.b.g, w), mix(e.a.b, e.b.b, w)};
      Entry& entry = palette_[w];
      entry.norm = 0;
      for (int j = 0; j < 3; ++j) {
        const int32_t qp = kErrorWeights[j][0] * p[0] + kErrorWeights[j][1] * p[1] + kErrorWeights[j][2] * p[2];
        entry.twice_qp[j] = 2 * qp;
        entry.norm += static_cast<uint32_t>(p[j] * qp);
      }
    }
  }

  uint32_t Weight(const Rgb8& c) const {
    const int32_t dot = (c.r - e_.a.r) * q_[0] + (c.g - e_.a.g) * q_[1] + (c.b - e_.a.b) * q_[2];
    if (dot <= 0) return 0;
    if (dot >= len2_) return kM;
    return static_cast<uint32_t>(double(2 * int64_t{kM} * dot + len2_) * inverse_ + 0x1p-38);
  }

  // BlockError(c, Interpolate(e, w)) from c's norm c^T Q c: (c - p)^T Q (c - p) = c^T Q c - 2 c^T Q p + p^T Q p,
  // the same integer, for three products instead of twelve (every term is below 2^31).
  uint32_t Error(const Rgb8& c, uint32_t norm, uint32_t w) const {
    const Entry& p = palette_[w];
    return norm + p.norm - static_cast<uint32_t>(c.r * p.twice_qp[0] + c.g * p.twice_qp[1] + c.b * p.twice_qp[2]);
  }

 private:
  struct Entry {  // for p = Interpolate(e, w)
    int32_t twice_qp[3];  // 2 Q p
    uint32_t norm;        // p^T Q p
  };
  Endpoints e_;
  std::array<int32_t, 3> q_;  // Q (B - A)
  int32_t len2_;
  double inverse_;
  std::array<Entry, kM + 1> palette_;  // for every weight, computed once per endpoints
};

// Weights and error for `ends`, then endpoints refined by least squares for those weights
// (with u = m - w, t = w: minimise sum(u A + t B - m c)^2 per channel); the better fit wins.
// The least-squares sums come from sum(w), sum(w^2) and sum(w c) (below 2^26): with n colors,
// sum(u t) = m sum(w) - sum(w^2), sum(u^2) = m^2 n - 2 m sum(w) + sum(w^2), sum(u c) = m sum(c) - sum(w c).
template <int kBits>
BlockFit FitWeights(const Rgb8* colors, const uint32_t* norms, uint32_t length, const int64_t sums[3], const Endpoints& ends,
                    uint64_t give_up_above) {
  constexpr int64_t m = Rebuilder<kBits>::kM;
  BlockFit best{ends, 0};
  const Rebuilder<kBits> first(ends);
  int32_t sum_w = 0, sum_ww = 0, wc[3] = {0, 0, 0};
  const uint64_t hopeless = give_up_above <= UINT64_MAX / kHopeless ? kHopeless * give_up_above : UINT64_MAX;
  for (uint32_t i = 0; i < length; ++i) {
    if (best.sse > hopeless) return {ends, give_up_above + 1};
    const uint32_t w = first.Weight(colors[i]);
    best.sse += first.Error(colors[i], norms[i], w);
    sum_w += static_cast<int32_t>(w), sum_ww += static_cast<int32_t>(w * w);
    wc[0] += static_cast<int32_t>(w) * colors[i].r, wc[1] += static_cast<int32_t>(w) * colors[i].g, wc[2] += static_cast<int32_t>(w) * colors[i].b;
  }
  const int64_t s11 = sum_ww, s01 = m * sum_w - sum_ww, s00 = m * m * int64_t{length} - 2 * m * sum_w + sum_ww;
  int64_t r0[3], r1[3];
  for (int k = 0; k < 3; ++k) r1[k] = wc[k], r0[k] = m * sums[k] - wc[k];
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
  const Rebuilder<kBits> second(refined);
  const uint64_t stop = std::min(best.sse, give_up_above);
  uint64_t sse = 0;
  for (uint32_t i = 0; i < length && sse <= stop; ++i) sse += second.Error(colors[i], norms[i], second.Weight(colors[i]));
  if (sse < best.sse) best = {refined, sse};
  return best;
}

}  // namespace

BlockFitter::BlockFitter(std::span<const Rgb8> colors) : colors_(colors), prefix_(colors.size() + 1), norms_(colors.size()) {
  prefix_[0].fill(0);
  for (size_t i = 0; i < colors.size(); ++i) {
    const uint32_t r = colors[i].r, g = colors[i].g, b = colors[i].b;
    const std::array<uint32_t, 9> add = {r, g, b, r * r, g * g, b * b, r * g, r * b, g * b};
    for (int k = 0; k < 9; ++k) prefix_[i + 1][k] = prefix_[i][k] + add[k];
    norms_[i] = BlockError(colors[i], Rgb8{0, 0, 0});
  }
}

BlockFitter::Sums BlockFitter::RangeSums(uint32_t begin, uint32_t end) const {
  Sums out;
  for (int k = 0; k < 3; ++k) out.s[k] = int64_t{prefix_[end][k]} - prefix_[begin][k];
  for (int k = 0; k < 6; ++k) out.ss[k] = int64_t{prefix_[end][3 + k]} - prefix_[begin][3 + k];
  return out;
}

BlockFit BlockFitter::Fit(uint32_t begin, uint32_t length, int bits, uint64_t give_up_above) const {
  const int64_t n = length;
  const Sums sums = RangeSums(begin, begin + length);
  // Covariance scaled by n^2: M[j][k] = n * sum(c_j c_k) - sum(c_j) sum(c_k).
  int64_t cov[3][3];
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 3; ++k) cov[j][k] = n * sums.ss[kPair[j][k]] - sums.s[j] * sums.s[k];
  }
  const int widest = cov[0][0] >= cov[1][1] ? (cov[0][0] >= cov[2][2] ? 0 : 2) : (cov[1][1] >= cov[2][2] ? 1 : 2);
  if (bits == 0 || cov[widest][widest] == 0) {
    // One color for the whole block: the mean, whose error follows from the sums alone:
    // sum over colors of (c - a)^T Q (c - a) = sum_jk Q_jk (ss_jk - a_j s_k - a_k s_j + n a_j a_k).
    int64_t a[3];
    const RoundDivider divide(n);
    for (int k = 0; k < 3; ++k) a[k] = divide(sums.s[k]);  // a mean of 0..255: never clamped
    int64_t sse = 0;
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        sse += kErrorWeights[j][k] * (sums.ss[kPair[j][k]] - a[j] * sums.s[k] - a[k] * sums.s[j] + n * a[j] * a[k]);
      }
    }
    const Rgb8 c{Clamp255(a[0]), Clamp255(a[1]), Clamp255(a[2])};
    return {{c, c}, static_cast<uint64_t>(sse)};
  }
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
  const Rgb8* colors = colors_.data() + begin;
  const int32_t qa32[3] = {static_cast<int32_t>(qa[0]), static_cast<int32_t>(qa[1]), static_cast<int32_t>(qa[2])};
  int32_t lowest = INT32_MAX, highest = INT32_MIN;
  for (uint32_t i = 0; i < length; ++i) {
    const int32_t p = colors[i].r * qa32[0] + colors[i].g * qa32[1] + colors[i].b * qa32[2];
    lowest = std::min(lowest, p), highest = std::max(highest, p);
  }
  const int64_t centre = sums.s[0] * qa[0] + sums.s[1] * qa[1] + sums.s[2] * qa[2];
  const int64_t lo = std::min<int64_t>(0, n * lowest - centre), hi = std::max<int64_t>(0, n * highest - centre);
  const int64_t axis2 = axis[0] * qa[0] + axis[1] * qa[1] + axis[2] * qa[2];
  const RoundDivider divide(n * axis2);
  const auto along = [&](int64_t t, int k) { return divide(sums.s[k] * axis2 + t * axis[k]); };
  const Endpoints ends{{along(lo, 0), along(lo, 1), along(lo, 2)}, {along(hi, 0), along(hi, 1), along(hi, 2)}};

  const uint32_t* norms = norms_.data() + begin;
  switch (bits) {
    case 1: return FitWeights<1>(colors, norms, length, sums.s, ends, give_up_above);
    case 2: return FitWeights<2>(colors, norms, length, sums.s, ends, give_up_above);
    case 3: return FitWeights<3>(colors, norms, length, sums.s, ends, give_up_above);
    default: return FitWeights<4>(colors, norms, length, sums.s, ends, give_up_above);
  }
}

}  // namespace pointdag
