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
  int dx, dy, dz, weight;
};

// The 26 neighbours, nearer ones weighing more (faces 4, edges 2, corners 1).
constexpr std::array<Offset, 26> kOffsets = [] {
  std::array<Offset, 26> out{};
  int n = 0;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        const int far = (dx != 0) + (dy != 0) + (dz != 0);
        if (far != 0) out[n++] = {dx, dy, dz, 1 << (3 - far)};
      }
    }
  }
  return out;
}();

struct Prediction {
  int g = 128, rg = 0, bg = 0;              // G, R-G and B-G
  int spread_g = 0, spread_rg = 0, spread_bg = 0;  // the neighbours' weighted disagreement with them
  bool none = true;                         // nothing to predict from
};

int Div(int sum, int weight) { return (sum + weight / 2) / weight; }

// Up to 27 weighted colors already decoded, folded into a prediction.
class Gather {
 public:
  void Add(const Rgb8& c, int weight) {
    if (n_ < items_.size()) items_[n_++] = {c, weight};
  }
  Prediction Predict() const {
    Prediction p;
    if (n_ == 0) return p;
    int w = 0, g = 0, rg = 0, bg = 0;
    for (size_t i = 0; i < n_; ++i) {
      const auto& [c, wi] = items_[i];
      w += wi;
      g += wi * c.g;
      rg += wi * (c.r - c.g);
      bg += wi * (c.b - c.g);
    }
    p = {Div(g, w), Div(rg, w), Div(bg, w), 0, 0, 0, false};
    int sg = 0, srg = 0, sbg = 0;
    for (size_t i = 0; i < n_; ++i) {
      const auto& [c, wi] = items_[i];
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
  std::array<std::pair<Rgb8, int>, 27> items_{};
  size_t n_ = 0;
};

// The prediction of color i from colors [0, i), which both sides know.
class Predictor {
 public:
  explicit Predictor(std::span<const uint64_t> morton) : morton_(morton) {
    if (!morton.empty()) table_ = std::make_unique<MortonTable>(morton);
  }
  Prediction operator()(std::span<const Rgb8> colors, size_t i) const {
    Gather gather;
    if (table_) {
      const auto [x, y, z] = MortonDecode(morton_[i]);
      for (const Offset& o : kOffsets) {
        const int64_t nx = int64_t{x} + o.dx, ny = int64_t{y} + o.dy, nz = int64_t{z} + o.dz;
        if (nx < 0 || ny < 0 || nz < 0 || nx >= (1 << kMaxDepth) || ny >= (1 << kMaxDepth) || nz >= (1 << kMaxDepth)) {
          continue;
        }
        const uint64_t code = MortonEncode(static_cast<uint32_t>(nx), static_cast<uint32_t>(ny), static_cast<uint32_t>(nz));
        if (code >= morton_[i]) continue;  // not decoded yet
        const int64_t j = table_->Find(code);
        if (j >= 0 && static_cast<size_t>(j) < i) gather.Add(colors[j], o.weight);
      }
    }
    Prediction p = gather.Predict();
    if (p.none && i > 0) {
      Gather previous;
      previous.Add(colors[i - 1], 1);
      p = previous.Predict();
      p.none = true;  // a weaker guess: its own contexts
    }
    return p;
  }

 private:
  std::span<const uint64_t> morton_;
  std::unique_ptr<MortonTable> table_;
};

constexpr int kSpreadBuckets = 7, kResidualBuckets = 6;
int Bucket(int v, int buckets) { return std::min(buckets - 1, static_cast<int>(std::bit_width(static_cast<unsigned>(v)))); }

struct Models {
  std::array<GammaModel, 2 * kSpreadBuckets> g;
  std::array<GammaModel, 2 * kSpreadBuckets * kResidualBuckets> r, b;
};

int Wrap(int v) { return ((v + 128) & 255) - 128; }
uint8_t Clamp(int v) { return static_cast<uint8_t>(std::clamp(v, 0, 255)); }

// One loop for both sides: `io.Code(model, residual)` writes the residual (encoder) or returns the
// decoded one (decoder), and `colors[i]` is rebuilt from it, so both see the same past.
template <class Io>
void CodeColors(Io& io, std::span<Rgb8> colors, std::span<const uint64_t> morton) {
  auto models = std::make_unique<Models>();
  const Predictor predict(morton);
  for (size_t i = 0; i < colors.size(); ++i) {
    const Prediction p = predict(colors, i);
    Rgb8& c = colors[i];
    const int ctx = Bucket(p.spread_g, kSpreadBuckets) + (p.none ? kSpreadBuckets : 0);
    const int eg = io.Code(models->g[ctx], Wrap(c.g - p.g));
    c.g = static_cast<uint8_t>((p.g + eg) & 255);
    const int near = Bucket(std::abs(eg), kResidualBuckets) + (p.none ? kResidualBuckets * kSpreadBuckets : 0);
    const uint8_t pr = Clamp(c.g + p.rg), pb = Clamp(c.g + p.bg);
    const int er = io.Code(models->r[Bucket(p.spread_rg, kSpreadBuckets) * kResidualBuckets + near], Wrap(c.r - pr));
    c.r = static_cast<uint8_t>((pr + er) & 255);
    const int eb = io.Code(models->b[Bucket(p.spread_bg, kSpreadBuckets) * kResidualBuckets + near], Wrap(c.b - pb));
    c.b = static_cast<uint8_t>((pb + eb) & 255);
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
  if (colors.size() >= (uint64_t{1} << 32)) return InvalidArgument("lossless colors: too many colors");
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
    return InvalidArgument("lossless colors predicted from neighbours need the voxels' Morton codes");
  }
  std::vector<Rgb8> colors(count);
  DecodeIo io{BinaryRangeDecoder(coded)};
  CodeColors(io, colors, mode == kModeNeighbours ? morton : std::span<const uint64_t>{});
  if (io.rc.overrun()) return Truncated("lossless colors stream ends early");
  return colors;
}

}  // namespace pointdag
