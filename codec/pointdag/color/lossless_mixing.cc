#include "pointdag/color/lossless_mixing.h"

#include <algorithm>
#include <array>
#include <memory>

#include "pointdag/color/lossless_neighbourhood.h"
#include "pointdag/color/lossless_predict.h"
#include "pointdag/entropy/binary_range_coder.h"
#include "pointdag/entropy/logistic.h"

namespace pointdag::lossless {
namespace {

// A residual e (-128..127; a decoder may read -255..255, wrapped alike) as binary decisions: e = 0?,
// e < 0?, then the bit length L of |e| in unary ("L > l?" for l = 1..7, none after 8), the mixed
// decisions; then the L - 1 bits below |e|'s leading one, each with one plain model.
constexpr int kMixedDecisions = 9, kModels = 4, kMixContexts = 8, kMaxLength = 8;

// One channel's coder: each mixed decision's probability is the logistic mix of four context
// models' (the caller picks their contexts per residual) and a bias, with weights per decision and
// mixing context, trained on every bit.
class ChannelCoder {
 public:
  // Contexts per model.
  explicit ChannelCoder(const std::array<int, kModels>& sizes) {
    for (int k = 0; k < kModels; ++k) models_[k].resize(static_cast<size_t>(sizes[k]) * kMixedDecisions);
    Reset();
  }
  // As new, without allocating.
  void Reset() {
    for (auto& models : models_) std::fill(models.begin(), models.end(), SteadyBitModel{});
    for (auto& w : weights_) w = {kInitialWeight, kInitialWeight, kInitialWeight, kInitialWeight, 0};
    plain_.fill(SteadyBitModel{});
  }
  std::array<int, kModels> context{};
  int mix_context = 0;  // 0..7

  template <class Io>
  int Code(Io& io, int e) {
    if (Bit(io, 0, e == 0)) return 0;
    const int negative = Bit(io, 1, e < 0);
    const int magnitude = std::abs(e);
    const int length = std::bit_width(static_cast<unsigned>(magnitude));
    int l = 1;
    while (l < kMaxLength && Bit(io, 1 + l, length > l)) ++l;
    int v = 1;
    for (int j = 0; j < l - 1; ++j) {
      SteadyBitModel& m = plain_[((l - 2) * (kMaxLength - 1) + j) * kMixContexts + mix_context];
      v = v << 1 | io.Bit(m, (magnitude >> (l - 2 - j)) & 1);
    }
    return negative ? -v : v;
  }

 private:
  static constexpr int32_t kInitialWeight = 65536 * 3 / (2 * kModels), kBias = 256, kMaxWeight = 1 << 22;

  template <class Io>
  int Bit(Io& io, int decision, int truth) {
    std::array<SteadyBitModel*, kModels> m;
    std::array<int32_t, kModels + 1> st;
    for (int k = 0; k < kModels; ++k) {
      m[k] = &models_[k][static_cast<size_t>(context[k]) * kMixedDecisions + decision];
      st[k] = kStretch[4096 - m[k]->P0()];
    }
    st[kModels] = kBias;
    std::array<int32_t, kModels + 1>& w = weights_[decision * kMixContexts + mix_context];
    int64_t dot = 0;
    for (int k = 0; k <= kModels; ++k) dot += int64_t{w[k]} * st[k];
    const int32_t p1 = kSquashTable[static_cast<size_t>(std::clamp<int64_t>(dot >> 16, -2047, 2047) + 2047)];
    FixedP0 mixed{static_cast<uint32_t>(4096 - p1)};
    const int bit = io.Bit(mixed, truth);
    const int32_t err = (bit << 12) - p1;
    for (int k = 0; k <= kModels; ++k) w[k] = std::clamp(w[k] + ((st[k] * err) >> 12), -kMaxWeight, kMaxWeight);
    for (int k = 0; k < kModels; ++k) m[k]->Update(bit);
    return bit;
  }

  std::array<std::vector<SteadyBitModel>, kModels> models_;
  std::array<std::array<int32_t, kModels + 1>, kMixedDecisions * kMixContexts> weights_;
  std::array<SteadyBitModel, (kMaxLength - 1) * (kMaxLength - 1) * kMixContexts> plain_{};
};

constexpr int kSpreadBuckets = 7, kResidualBuckets = 6;

// One step for both sides: `io.Bit(model, bit)` writes the bit (encoder) or returns the decoded
// one (decoder), and color i is rebuilt from the residuals, so both see the same past.
// The contexts, with s(x) = b₇(spread of x) + 7·unpredicted (b_k as Bucket) and eg, er the coded
// residuals of G and R: G by s(G); s(G) and the previous voxel's |eg|; nothing; and the chroma's
// and G's spreads. R (B alike, with its own spread) by s(R-G) and |eg|; s(R-G), eg's sign and |eg|;
// nothing (for B: er); and G's spread and |eg|.
class MixedCoder {
 public:
  explicit MixedCoder(std::span<const uint64_t> morton) : predict_(morton, 3) {}

  void Reset() {
    g_.Reset(), red_.Reset(), blue_.Reset();
    predict_.Reset();
    share_r_ = share_b_ = Share{};
    last_eg_ = 0;
  }

  // Color i (the decoder's colors[i] is not read) from colors [0, i).
  template <class Io>
  Rgb8 Code(Io& io, std::span<const Rgb8> colors, size_t i, const Neighbourhood& around, Predicted* log = nullptr) {
    return CodeFrom(io, colors[i], i, predict_(colors, i, around, log));
  }
  template <class Io>
  Rgb8 Replay(Io& io, std::span<const Rgb8> colors, size_t i, const Predicted& known) {
    return CodeFrom(io, colors[i], i, predict_.Replay(i, known));
  }

 private:
  template <class Io>
  Rgb8 CodeFrom(Io& io, Rgb8 c, size_t i, const Prediction& p) {
    const int unpredicted = p.none ? kSpreadBuckets : 0;
    const int sg = Bucket(p.spread_g, kSpreadBuckets) + unpredicted;
    g_.context = {sg, sg * 8 + Bucket(std::abs(last_eg_), 8), 0, Bucket(p.spread_rg + p.spread_bg, 8) * 8 + Bucket(p.spread_g, 8)};
    g_.mix_context = std::min(kMixContexts - 1, sg);
    const int eg = g_.Code(io, Wrap(c.g - p.g));
    c.g = static_cast<uint8_t>((p.g + eg) & 255);
    last_eg_ = eg;
    // G's miss unwrapped: what R and B share of it.
    const int dg = c.g - p.g, aeg = Bucket(std::abs(eg), kResidualBuckets), seg = (eg > 0 ? 8 : 0) + Bucket(std::abs(eg), 8);
    const uint8_t pr = Clamp(p.g + p.rg + share_r_.Of(dg));
    const int srg = Bucket(p.spread_rg, kSpreadBuckets) + unpredicted;
    red_.context = {srg * kR + aeg, srg * 16 + seg, 0, Bucket(p.spread_g, 8) * kR + aeg};
    red_.mix_context = std::min(kMixContexts - 1, srg);
    const int er = red_.Code(io, Wrap(c.r - pr));
    c.r = static_cast<uint8_t>((pr + er) & 255);
    const uint8_t pb = Clamp(p.g + p.bg + share_b_.Of(dg));
    const int sbg = Bucket(p.spread_bg, kSpreadBuckets) + unpredicted;
    blue_.context = {sbg * kR + aeg, sbg * 16 + seg, std::min(15, std::abs(er)) * 2 + (er > 0 ? 1 : 0), Bucket(p.spread_g, 8) * kR + aeg};
    blue_.mix_context = std::min(kMixContexts - 1, sbg);
    const int eb = blue_.Code(io, Wrap(c.b - pb));
    c.b = static_cast<uint8_t>((pb + eb) & 255);
    share_r_.Learn(dg, c.r - (p.g + p.rg));
    share_b_.Learn(dg, c.b - (p.g + p.bg));
    predict_.Record(i, c);
    return c;
  }

  static constexpr int kS = 2 * kSpreadBuckets, kR = kResidualBuckets;
  ChannelCoder g_{{kS, kS * 8, 1, 64}};
  ChannelCoder red_{{kS * kR, kS * 16, 1, 8 * kR}};
  ChannelCoder blue_{{kS * kR, kS * 16, 32, 8 * kR}};
  Predictor predict_;
  Share share_r_, share_b_;
  int last_eg_ = 0;
};

struct EncodeIo {
  BinaryRangeEncoder rc;
  template <class Model>
  int Bit(Model& m, int bit) {
    rc.Encode(m, bit);
    return bit;
  }
};

struct DecodeIo {
  BinaryRangeDecoder rc;
  template <class Model>
  int Bit(Model& m, int) {
    return rc.Decode(m);
  }
};

}  // namespace

struct MixedEncoder::State {
  explicit State(std::span<const uint64_t> morton) : coder(morton) {}
  MixedCoder coder;
  EncodeIo io;
};

MixedEncoder::MixedEncoder(std::span<const uint64_t> morton) : state_(std::make_unique<State>(morton)) {}
MixedEncoder::~MixedEncoder() = default;
MixedEncoder::MixedEncoder(MixedEncoder&&) noexcept = default;
MixedEncoder& MixedEncoder::operator=(MixedEncoder&&) noexcept = default;

void MixedEncoder::Reset() {
  state_->coder.Reset();
  state_->io = EncodeIo{};
}

void MixedEncoder::Code(std::span<const Rgb8> colors, size_t i, const Neighbourhood& around, Predicted* log) {
  state_->coder.Code(state_->io, colors, i, around, log);
}

void MixedEncoder::Replay(std::span<const Rgb8> colors, size_t i, const Predicted& known) {
  state_->coder.Replay(state_->io, colors, i, known);
}

size_t MixedEncoder::FinishedSize() const {
  BinaryRangeEncoder copy = state_->io.rc;
  return copy.Finish().size();
}

std::vector<uint8_t> MixedEncoder::Finish() { return state_->io.rc.Finish(); }

std::vector<uint8_t> EncodeMixed(std::span<const Rgb8> colors, std::span<const uint64_t> morton, bool columns) {
  MixedEncoder encoder(morton);
  if (morton.empty()) {
    for (size_t i = 0; i < colors.size(); ++i) encoder.Code(colors, i, {});
  } else {
    NeighbourhoodSearch search(morton, 3, columns);
    for (size_t i = 0; i < colors.size(); ++i) encoder.Code(colors, i, search.Next(i));
  }
  return encoder.Finish();
}

bool DecodeMixed(std::span<const uint8_t> coded, std::span<Rgb8> colors, std::span<const uint64_t> morton,
                 bool columns) {
  DecodeIo io{BinaryRangeDecoder(coded)};
  auto coder = std::make_unique<MixedCoder>(morton);
  if (morton.empty()) {
    for (size_t i = 0; i < colors.size(); ++i) colors[i] = coder->Code(io, colors, i, {});
  } else {
    NeighbourhoodSearch search(morton, 3, columns);
    for (size_t i = 0; i < colors.size(); ++i) colors[i] = coder->Code(io, colors, i, search.Next(i));
  }
  return io.rc.consumed_exactly();
}

}  // namespace pointdag::lossless
