#include "pointdag/color/block_fit.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace pointdag {
namespace {

// Sums index: r g b, then rr gg bb rg rb gb; kPair[j][k] finds the product sum of channels j, k.
constexpr int kPair[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
constexpr int kAxisBits = 10;  // power iteration keeps the axis below 2^10 per component
constexpr int kPowerIterations = 8;

int64_t FloorDiv(int64_t a, int64_t b) {  // b > 0
  const int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

int64_t RoundDiv(int64_t a, int64_t b) { return FloorDiv(2 * a + b, 2 * b); }  // half up; b > 0

uint8_t Clamp255(int64_t v) { return static_cast<uint8_t>(std::clamp<int64_t>(v, 0, 255)); }

int Channel(const Rgb8& c, int k) { return k == 0 ? c.r : k == 1 ? c.g : c.b; }

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
    const auto mix = [](uint32_t a, uint32_t b, uint32_t w) { return static_cast<uint8_t>((a * (kM - w) + b * w + kM / 2) / kM); };
    for (uint32_t w = 0; w <= kM; ++w) palette_[w] = {mix(e.a.r, e.b.r, w), mix(e.a.g, e.b.g, w), mix(e.a.b, e.b.b, w)};
  }

  uint32_t Weight(const Rgb8& c) const {
    const int32_t dot = (c.r - e_.a.r) * q_[0] + (c.g - e_.a.g) * q_[1] + (c.b - e_.a.b) * q_[2];
    if (dot <= 0) return 0;
    if (dot >= len2_) return kM;
    return static_cast<uint32_t>(double(2 * int64_t{kM} * dot + len2_) * inverse_ + 0x1p-38);
  }

  Rgb8 Color(uint32_t w) const { return palette_[w]; }

 private:
  Endpoints e_;
  std::array<int32_t, 3> q_;  // Q (B - A)
  int32_t len2_;
  double inverse_;
  std::array<Rgb8, kM + 1> palette_;  // Interpolate for every weight, computed once per endpoints
};

// Weights and error for `ends`, then endpoints refined by least squares for those weights
// (with u = m - w, t = w: minimise sum(u A + t B - m c)^2 per channel); the better fit wins.
template <int kBits>
BlockFit FitWeights(const Rgb8* colors, uint32_t length, const Endpoints& ends, uint64_t give_up_above) {
  constexpr int64_t m = Rebuilder<kBits>::kM;
  BlockFit best{ends, 0};
  const Rebuilder<kBits> first(ends);
  int64_t s00 = 0, s01 = 0, s11 = 0, r0[3] = {0, 0, 0}, r1[3] = {0, 0, 0};
  for (uint32_t i = 0; i < length; ++i) {
    const uint32_t w = first.Weight(colors[i]);
    best.sse += BlockError(colors[i], first.Color(w));
    const int64_t u = m - w, t = w;
    s00 += u * u, s01 += u * t, s11 += t * t;
    for (int k = 0; k < 3; ++k) r0[k] += u * Channel(colors[i], k), r1[k] += t * Channel(colors[i], k);
  }
  const int64_t det = s00 * s11 - s01 * s01;
  if (det <= 0 || best.sse == 0) return best;
  uint8_t a[3], b[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = Clamp255(RoundDiv(m * (s11 * r0[k] - s01 * r1[k]), det));
    b[k] = Clamp255(RoundDiv(m * (s00 * r1[k] - s01 * r0[k]), det));
  }
  const Endpoints refined{{a[0], a[1], a[2]}, {b[0], b[1], b[2]}};
  if (refined == best.ends) return best;
  const Rebuilder<kBits> second(refined);
  const uint64_t stop = std::min(best.sse, give_up_above);
  uint64_t sse = 0;
  for (uint32_t i = 0; i < length && sse <= stop; ++i) sse += BlockError(colors[i], second.Color(second.Weight(colors[i])));
  if (sse < best.sse) best = {refined, sse};
  return best;
}

// Below the smallest eigenvalue of kErrorWeights (139.4): BlockError >= this x the RGB squared error.
constexpr double kErrorFloor = 136.0;

// Whether no fit with any bits can reach `give_up_above` (a BlockError sum, so at least kErrorFloor
// times the RGB squared error bounded here), known from the covariance alone. Every
// rebuilt color lies within sqrt(3)/2 of the segment A-B (Interpolate rounds each channel to within
// 1/2), so with D the colors' squared distance to that line, sse >= D - sqrt(3 n D) once D >= 3n/4; and D is at
// least the scatter off the principal axis, lambda2 + lambda3 = s, which the characteristic
// polynomial bounds: e2 <= lambda1 s + s^2 / 4 = (e1 - s) s + s^2 / 4 gives s >= 2/3 (e1 - sqrt(e1^2 - 3 e2)).
// Only ever rejects fits that would fail, so results do not depend on it.
bool CannotReach(const int64_t cov[3][3], int64_t n, uint64_t give_up_above) {
  const double m[3][3] = {{double(cov[0][0]), double(cov[0][1]), double(cov[0][2])},
                          {double(cov[1][0]), double(cov[1][1]), double(cov[1][2])},
                          {double(cov[2][0]), double(cov[2][1]), double(cov[2][2])}};
  const double e1 = m[0][0] + m[1][1] + m[2][2];
  const double e2 = m[0][0] * m[1][1] - m[0][1] * m[0][1] + m[0][0] * m[2][2] - m[0][2] * m[0][2] + m[1][1] * m[2][2] - m[1][2] * m[1][2];
  const double s = 2.0 / 3.0 * (e1 - std::sqrt(std::max(0.0, e1 * e1 - 3 * e2))) - 1e-6 * e1;  // margin for rounding
  const double scatter = s / double(n);  // cov is n times the scatter matrix
  if (scatter < 0.75 * double(n)) return false;
  return kErrorFloor * (scatter - std::sqrt(3.0 * double(n) * scatter)) > double(give_up_above);
}

}  // namespace

BlockFitter::BlockFitter(std::span<const Rgb8> colors) : colors_(colors), prefix_(colors.size() + 1) {
  prefix_[0].fill(0);
  for (size_t i = 0; i < colors.size(); ++i) {
    const uint32_t r = colors[i].r, g = colors[i].g, b = colors[i].b;
    const std::array<uint32_t, 9> add = {r, g, b, r * r, g * g, b * b, r * g, r * b, g * b};
    for (int k = 0; k < 9; ++k) prefix_[i + 1][k] = prefix_[i][k] + add[k];
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
    for (int k = 0; k < 3; ++k) a[k] = RoundDiv(sums.s[k], n);
    int64_t sse = 0;
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        sse += kErrorWeights[j][k] * (sums.ss[kPair[j][k]] - a[j] * sums.s[k] - a[k] * sums.s[j] + n * a[j] * a[k]);
      }
    }
    const Rgb8 c{Clamp255(a[0]), Clamp255(a[1]), Clamp255(a[2])};
    return {{c, c}, static_cast<uint64_t>(sse)};
  }
  if (give_up_above != UINT64_MAX && CannotReach(cov, n, give_up_above)) return {{}, give_up_above + 1};
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
    std::copy(next, next + 3, axis);
  }
  // Extent of the colors along the axis (projections (n c - s)^T Q axis), endpoints at both ends.
  weigh();
  const Rgb8* colors = colors_.data() + begin;
  int64_t lo = 0, hi = 0;
  for (uint32_t i = 0; i < length; ++i) {
    int64_t t = 0;
    for (int k = 0; k < 3; ++k) t += (n * Channel(colors[i], k) - sums.s[k]) * qa[k];
    lo = std::min(lo, t), hi = std::max(hi, t);
  }
  const int64_t axis2 = axis[0] * qa[0] + axis[1] * qa[1] + axis[2] * qa[2];
  const auto along = [&](int64_t t, int k) { return Clamp255(RoundDiv(sums.s[k] * axis2 + t * axis[k], n * axis2)); };
  const Endpoints ends{{along(lo, 0), along(lo, 1), along(lo, 2)}, {along(hi, 0), along(hi, 1), along(hi, 2)}};

  switch (bits) {
    case 1: return FitWeights<1>(colors, length, ends, give_up_above);
    case 2: return FitWeights<2>(colors, length, ends, give_up_above);
    case 3: return FitWeights<3>(colors, length, ends, give_up_above);
    default: return FitWeights<4>(colors, length, ends, give_up_above);
  }
}

}  // namespace pointdag
