#include "pointdag/color/lossless_context.h"

#include <algorithm>
#include <array>
#include <bit>
#include <memory>

#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/entropy/varint.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

constexpr uint8_t kVersion = 2;
constexpr uint8_t kModePrevious = 0, kModeNeighbours = 1;
// Each color costs at least three binary decisions of p <= 4095/4096 (0.00106 bits): 7570 a byte.
constexpr uint64_t kMaxColorsPerByte = 8192;
constexpr int kMaxGammaLength = 9;  // zigzag residuals of -128..127 are 1..256

// Open addressing from a Morton code to its color index; keys are read back from the codes
// themselves, so a slot is one index (+1, 0 = empty).
class MortonTable {
 public:
  explicit MortonTable(std::span<const uint64_t> morton) : morton_(morton) {
    const size_t capacity = std::bit_ceil(std::max<size_t>(16, 2 * morton.size()));
    slots_.assign(capacity, 0);
    mask_ = capacity - 1;
    for (size_t i = 0; i < morton.size(); ++i) {
      size_t s = Hash(morton[i]) & mask_;
      while (slots_[s] != 0) s = (s + 1) & mask_;
      slots_[s] = static_cast<uint32_t>(i + 1);
    }
  }
  // The index of `code`, or -1.
  int64_t Find(uint64_t code) const {
    for (size_t s = Hash(code) & mask_; slots_[s] != 0; s = (s + 1) & mask_) {
      if (morton_[slots_[s] - 1] == code) return slots_[s] - 1;
    }
    return -1;
  }

 private:
  static size_t Hash(uint64_t code) { return static_cast<size_t>((code * 0x9E3779B97F4A7C15ull) >> 20); }
  std::span<const uint64_t> morton_;
  std::vector<uint32_t> slots_;
  size_t mask_ = 0;
};

struct Offset {
  int dx, dy, dz, d2;  // d2: squared distance
};

// The neighbours with |dx|, |dy|, |dz| <= `radius`, minus those within `inner` (a shell).
template <int radius, int inner>
constexpr auto Shell() {
  constexpr int kCount = (2 * radius + 1) * (2 * radius + 1) * (2 * radius + 1) - (2 * inner + 1) * (2 * inner + 1) * (2 * inner + 1);
  std::array<Offset, kCount> out{};
  int n = 0;
  for (int dx = -radius; dx <= radius; ++dx) {
    for (int dy = -radius; dy <= radius; ++dy) {
      for (int dz = -radius; dz <= radius; ++dz) {
        const bool outside = dx < -inner || dx > inner || dy < -inner || dy > inner || dz < -inner || dz > inner;
        if (outside) out[n++] = {dx, dy, dz, dx * dx + dy * dy + dz * dz};
      }
    }
  }
  return out;
}
constexpr int kRadius = 2, kFarRadius = 4;
constexpr auto kOffsets = Shell<kRadius, 0>();
// Searched only for a voxel with no decoded neighbour within kRadius (sparse scans).
constexpr auto kFarOffsets = Shell<kFarRadius, kRadius>();
constexpr int kOffsetCount = static_cast<int>(std::max(kOffsets.size(), kFarOffsets.size()));

struct Prediction {
  int g = 128, rg = 0, bg = 0;              // G, R-G and B-G
  int spread_g = 0, spread_rg = 0, spread_bg = 0;  // the neighbours' weighted disagreement with them
  bool none = true;                         // nothing to predict from
};

int Div(int sum, int weight) { return (sum + weight / 2) / weight; }

// Weights by squared distance (index): the near set averages the 26 adjacent voxels, nearer ones
// weighing more; the wide one averages out more noise over the 5x5x5 block.
using Weights = std::array<int, 3 * kFarRadius * kFarRadius + 1>;
constexpr Weights kNear = {0, 4, 2, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0};
constexpr Weights kWide = {0, 12, 6, 4, 3, 2, 2, 0, 1, 1, 0, 0, 1};
// Beyond kRadius, for voxels with nothing nearer: max(1, 64 / d²) (d² from 9 to 3·kFarRadius²).
constexpr Weights kFar = [] {
  Weights w{};
  for (size_t d2 = 9; d2 < w.size(); ++d2) w[d2] = std::max<int>(1, static_cast<int>(64 / d2));
  return w;
}();

// The decoded neighbours of a voxel (index and squared distance), folded into predictions.
class Gather {
 public:
  void Clear() { n_ = 0; }
  void Add(size_t j, int d2) {
    if (n_ < items_.size()) items_[n_++] = {j, d2};
  }
  size_t size() const { return n_; }
  std::pair<size_t, int> operator[](size_t k) const { return items_[k]; }
  Prediction Predict(std::span<const Rgb8> colors, const Weights& weights) const {
    Prediction p;
    int w = 0, g = 0, rg = 0, bg = 0;
    for (size_t i = 0; i < n_; ++i) {
      const Rgb8 c = colors[items_[i].first];
      const int wi = weights[items_[i].second];
      w += wi;
      g += wi * c.g;
      rg += wi * (c.r - c.g);
      bg += wi * (c.b - c.g);
    }
    if (w == 0) return p;
    p = {Div(g, w), Div(rg, w), Div(bg, w), 0, 0, 0, false};
    int sg = 0, srg = 0, sbg = 0;
    for (size_t i = 0; i < n_; ++i) {
      const Rgb8 c = colors[items_[i].first];
      const int wi = weights[items_[i].second];
      sg += wi * std::abs(c.g - p.g);
      srg += wi * std::abs(c.r - c.g - p.rg);
      sbg += wi * std::abs(c.b - c.g - p.bg);
    }
    p.spread_g = Div(sg, w);
    p.spread_rg = Div(srg, w);
    p.spread_bg = Div(sbg, w);
    return p;
  }

 private:
  std::array<std::pair<size_t, int>, kOffsetCount> items_{};
  size_t n_ = 0;
};

int Miss(const Prediction& p, const Rgb8& c) {
  return std::abs(c.g - p.g) + std::abs(c.r - c.g - p.rg) + std::abs(c.b - c.g - p.bg);
}

// The prediction of color i from colors [0, i), which both sides know. Both weightings are tried
// on every voxel; the one that missed less on the adjacent decoded voxels predicts the next.
class Predictor {
 public:
  explicit Predictor(std::span<const uint64_t> morton) : morton_(morton) {
    if (!morton.empty()) {
      table_ = std::make_unique<MortonTable>(morton);
      misses_.resize(morton.size());
    }
  }
  Prediction operator()(std::span<const Rgb8> colors, size_t i) {
    Gather& gather = gather_;  // a member: its array is not cleared per voxel
    gather.Clear();
    if (table_) {
      Collect(i, kOffsets, gather);
      near_ = gather.Predict(colors, kNear);
      wide_ = gather.Predict(colors, kWide);
      int near_miss = 0, wide_miss = 0;
      for (size_t k = 0; k < gather.size(); ++k) {
        if (gather[k].second > 3) continue;
        near_miss += misses_[gather[k].first][0];
        wide_miss += misses_[gather[k].first][1];
      }
      const Prediction& best = near_.none || (!wide_.none && wide_miss <= near_miss) ? wide_ : near_;
      if (!best.none) return best;
      Collect(i, kFarOffsets, gather);
      const Prediction far = gather.Predict(colors, kFar);
      if (!far.none) return far;
    }
    Prediction p;
    if (i > 0) {
      const Rgb8 c = colors[i - 1];
      p = {c.g, c.r - c.g, c.b - c.g, 0, 0, 0, true};  // a weaker guess: its own contexts
    }
    return p;
  }
  // The decoded voxels at `offsets` from voxel i.
  template <class Offsets>
  void Collect(size_t i, const Offsets& offsets, Gather& gather) const {
    const auto [x, y, z] = MortonDecode(morton_[i]);
    for (const Offset& o : offsets) {
      const int64_t nx = int64_t{x} + o.dx, ny = int64_t{y} + o.dy, nz = int64_t{z} + o.dz;
      if (nx < 0 || ny < 0 || nz < 0 || nx >= (1 << kMaxDepth) || ny >= (1 << kMaxDepth) || nz >= (1 << kMaxDepth)) {
        continue;
      }
      const uint64_t code = MortonEncode(static_cast<uint32_t>(nx), static_cast<uint32_t>(ny), static_cast<uint32_t>(nz));
      if (code >= morton_[i]) continue;  // not decoded yet
      const int64_t j = table_->Find(code);
      if (j >= 0 && static_cast<size_t>(j) < i) gather.Add(static_cast<size_t>(j), o.d2);
    }
  }
  // After color i is known: how far each weighting was from it.
  void Record(size_t i, const Rgb8& c) {
    if (misses_.empty()) return;
    misses_[i] = {static_cast<uint16_t>(near_.none ? 0 : Miss(near_, c)), static_cast<uint16_t>(wide_.none ? 0 : Miss(wide_, c))};
  }

 private:
  std::span<const uint64_t> morton_;
  std::unique_ptr<MortonTable> table_;
  std::vector<std::array<uint16_t, 2>> misses_;
  Prediction near_, wide_;
  Gather gather_;
};

constexpr int kSpreadBuckets = 7, kResidualBuckets = 6;
int Bucket(int v, int buckets) { return std::min(buckets - 1, static_cast<int>(std::bit_width(static_cast<unsigned>(v)))); }

struct Models {
  std::array<GammaModel, 2 * kSpreadBuckets> g;
  std::array<GammaModel, 2 * kSpreadBuckets * kResidualBuckets> r, b;
};

// How much of G's residual R (or B) shares: the least-squares slope of its own miss (from the
// neighbours' mean) on G's residual, over a decaying window, in 1/16 (0..1.25).
class Share {
 public:
  int Of(int eg) const {
    const int64_t slope = sxx_ > 0 ? std::clamp<int64_t>(16 * sxy_ / sxx_, 0, 20) : 16;
    return static_cast<int>((slope * eg + (eg >= 0 ? 8 : -8)) / 16);
  }
  void Learn(int eg, int miss) {
    constexpr int k = 4;
    sxy_ += int64_t{eg} * miss - (sxy_ >> k);
    sxx_ += int64_t{eg} * eg - (sxx_ >> k);
  }

 private:
  int64_t sxy_ = 0, sxx_ = 0;
};

int Wrap(int v) { return ((v + 128) & 255) - 128; }
uint8_t Clamp(int v) { return static_cast<uint8_t>(std::clamp(v, 0, 255)); }

// One loop for both sides: `io.Code(model, residual)` writes the residual (encoder) or returns the
// decoded one (decoder), and `colors[i]` is rebuilt from it, so both see the same past.
template <class Io>
void CodeColors(Io& io, std::span<Rgb8> colors, std::span<const uint64_t> morton) {
  auto models = std::make_unique<Models>();
  Predictor predict(morton);
  Share share_r, share_b;
  for (size_t i = 0; i < colors.size(); ++i) {
    const Prediction p = predict(colors, i);
    Rgb8& c = colors[i];
    const int ctx = Bucket(p.spread_g, kSpreadBuckets) + (p.none ? kSpreadBuckets : 0);
    const int eg = io.Code(models->g[ctx], Wrap(c.g - p.g));
    c.g = static_cast<uint8_t>((p.g + eg) & 255);
    const int near = Bucket(std::abs(eg), kResidualBuckets) + (p.none ? kResidualBuckets * kSpreadBuckets : 0);
    const uint8_t pr = Clamp(p.g + p.rg + share_r.Of(eg));
    const int er = io.Code(models->r[Bucket(p.spread_rg, kSpreadBuckets) * kResidualBuckets + near], Wrap(c.r - pr));
    c.r = static_cast<uint8_t>((pr + er) & 255);
    const uint8_t pb = Clamp(p.g + p.bg + share_b.Of(eg));
    const int eb = io.Code(models->b[Bucket(p.spread_bg, kSpreadBuckets) * kResidualBuckets + near], Wrap(c.b - pb));
    c.b = static_cast<uint8_t>((pb + eb) & 255);
    share_r.Learn(eg, c.r - (p.g + p.rg));
    share_b.Learn(eg, c.b - (p.g + p.bg));
    predict.Record(i, c);
  }
}

struct EncodeIo {
  BinaryRangeEncoder rc;
  int Code(GammaModel& m, int residual) {
    EncodeGamma(rc, m, ZigZag(residual), kMaxGammaLength);
    return residual;
  }
};

struct DecodeIo {
  BinaryRangeDecoder rc;
  int Code(GammaModel& m, int) { return UnZigZag(DecodeGamma(rc, m, kMaxGammaLength)); }
};

}  // namespace

StatusOr<std::vector<uint8_t>> EncodeLosslessContext(std::span<const Rgb8> colors, std::span<const uint64_t> morton) {
  if (!morton.empty() && morton.size() != colors.size()) return InvalidArgument("lossless colors: one Morton code per color");
  if (uint64_t{colors.size()} >= (uint64_t{1} << 32)) return InvalidArgument("lossless colors: too many colors");
  std::vector<uint8_t> out = {kVersion, morton.empty() ? kModePrevious : kModeNeighbours};
  PutVarint(out, colors.size());
  std::vector<Rgb8> scratch(colors.begin(), colors.end());
  EncodeIo io;
  CodeColors(io, scratch, morton);
  const std::vector<uint8_t> coded = io.rc.Finish();
  out.insert(out.end(), coded.begin(), coded.end());
  return out;
}

bool IsLosslessContextPayload(std::span<const uint8_t> payload) { return !payload.empty() && payload[0] == kVersion; }

StatusOr<std::vector<Rgb8>> DecodeLosslessContext(std::span<const uint8_t> payload, uint64_t count,
                                                  std::span<const uint64_t> morton) {
  if (payload.size() < 2) return Truncated("lossless colors header");
  if (payload[0] != kVersion) return Corrupt("lossless colors: unknown version " + std::to_string(payload[0]));
  const uint8_t mode = payload[1];
  if (mode != kModePrevious && mode != kModeNeighbours) return Corrupt("lossless colors: unknown mode");
  size_t pos = 2;
  uint64_t n = 0;
  if (!GetVarint(payload, pos, n)) return Truncated("lossless colors count");
  if (n != count) return Corrupt("lossless colors do not hold one RGB per voxel");
  if (count >= (uint64_t{1} << 32)) return ResourceLimit("lossless colors: too many colors");
  const std::span<const uint8_t> coded = payload.subspan(pos);
  if (count / kMaxColorsPerByte > coded.size() + 8) return Corrupt("lossless colors: more colors than the bytes can hold");
  if (mode == kModeNeighbours && morton.size() != count) {
    // Only leaf-mode colors are coded from neighbours: anywhere else the section is not what the
    // geometry says it is.
    return Corrupt("lossless colors predicted from neighbours, but there are no voxels' Morton codes for them");
  }
  std::vector<Rgb8> colors(count);
  DecodeIo io{BinaryRangeDecoder(coded)};
  CodeColors(io, colors, mode == kModeNeighbours ? morton : std::span<const uint64_t>{});
  if (!io.rc.consumed_exactly()) return Corrupt("lossless colors: the stream does not end where its colors do");
  return colors;
}

}  // namespace pointdag
