#include "pointdag/color/lossless_context.h"

#include <algorithm>
#include <array>
#include <memory>
#include <optional>

#include "pointdag/color/lossless_layout.h"
#include "pointdag/color/lossless_mixing.h"
#include "pointdag/color/lossless_neighbourhood.h"
#include "pointdag/color/lossless_predict.h"
#include "pointdag/color/lossless_transform.h"
#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/entropy/varint.h"

namespace pointdag {
namespace {

using namespace lossless;

constexpr uint8_t kModePrevious = 0, kModeNeighbours = 1;
// Each color costs at least three binary decisions of p <= 4095/4096 (0.00106 bits), in either
// version: 7570 a byte.
constexpr uint64_t kMaxColorsPerByte = 8192;
constexpr int kMaxGammaLength = 9;  // zigzag residuals of -128..127 are 1..256

constexpr int kSpreadBuckets = 7, kResidualBuckets = 6;

struct Models {
  std::array<GammaModel, 2 * kSpreadBuckets> g;
  std::array<GammaModel, 2 * kSpreadBuckets * kResidualBuckets> r, b;
};

// One loop for both sides: `io.Code(model, residual)` writes the residual (encoder) or returns the
// decoded one (decoder), and `colors[i]` is rebuilt from it, so both see the same past.
template <class Io>
void CodeColors(Io& io, std::span<Rgb8> colors, std::span<const uint64_t> morton) {
  auto models = std::make_unique<Models>();
  Predictor predict(morton, 2);
  std::optional<NeighbourhoodSearch> search;
  if (!morton.empty()) search.emplace(morton, 2, false);
  Share share_r, share_b;
  for (size_t i = 0; i < colors.size(); ++i) {
    const Prediction p = predict(colors, i, search ? search->Next(i) : Neighbourhood{});
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

std::vector<uint8_t> EncodeGammaResiduals(std::span<const Rgb8> colors, std::span<const uint64_t> morton) {
  std::vector<Rgb8> scratch(colors.begin(), colors.end());
  EncodeIo io;
  CodeColors(io, scratch, morton);
  return io.rc.Finish();
}

bool DecodeGammaResiduals(std::span<const uint8_t> coded, std::span<Rgb8> colors, std::span<const uint64_t> morton) {
  DecodeIo io{BinaryRangeDecoder(coded)};
  CodeColors(io, colors, morton);
  return io.rc.consumed_exactly();
}

}  // namespace

StatusOr<std::vector<uint8_t>> EncodeLosslessContext(std::span<const Rgb8> colors, std::span<const uint64_t> morton,
                                                     int version, std::optional<uint8_t> layout_byte) {
  if (!morton.empty() && morton.size() != colors.size()) return InvalidArgument("lossless colors: one Morton code per color");
  if (uint64_t{colors.size()} >= (uint64_t{1} << 32)) return InvalidArgument("lossless colors: too many colors");
  if (version < 2 || version > kLosslessContextVersion) return InvalidArgument("lossless colors: no version " + std::to_string(version));
  std::vector<uint8_t> out = {static_cast<uint8_t>(version), morton.empty() ? kModePrevious : kModeNeighbours};
  PutVarint(out, colors.size());
  Layout layout;  // version 3's: the coder of version 4 with order 0 and no columns
  if (version >= 4) {
    if (!layout_byte) {
      LaidOut chosen = EncodeChosenLayout(colors, morton);
      out.push_back(chosen.layout.Byte());
      out.insert(out.end(), chosen.coded.begin(), chosen.coded.end());
      return out;
    }
    if (!LayoutOf(*layout_byte, layout) || (layout.columns && morton.empty())) {
      return InvalidArgument("lossless colors: no layout " + std::to_string(*layout_byte));
    }
    out.push_back(layout.Byte());
  }
  const std::vector<uint8_t> coded = version == 2 ? EncodeGammaResiduals(colors, morton) : EncodeLaid(colors, morton, layout);
  out.insert(out.end(), coded.begin(), coded.end());
  return out;
}

bool IsLosslessContextPayload(std::span<const uint8_t> payload) {
  return !payload.empty() && payload[0] >= 2 && payload[0] <= kLosslessContextVersion;
}

StatusOr<std::vector<Rgb8>> DecodeLosslessContext(std::span<const uint8_t> payload, uint64_t count,
                                                  std::span<const uint64_t> morton) {
  if (payload.size() < 2) return Truncated("lossless colors header");
  if (!IsLosslessContextPayload(payload)) return Corrupt("lossless colors: unknown version " + std::to_string(payload[0]));
  const uint8_t mode = payload[1];
  if (mode != kModePrevious && mode != kModeNeighbours) return Corrupt("lossless colors: unknown mode");
  size_t pos = 2;
  uint64_t n = 0;
  if (!GetVarint(payload, pos, n)) return Truncated("lossless colors count");
  if (n != count) return Corrupt("lossless colors do not hold one RGB per voxel");
  if (count >= (uint64_t{1} << 32)) return ResourceLimit("lossless colors: too many colors");
  Layout layout;
  if (payload[0] >= 4) {
    if (pos >= payload.size()) return Truncated("lossless colors layout");
    if (!LayoutOf(payload[pos++], layout)) return Corrupt("lossless colors: unknown layout " + std::to_string(payload[pos - 1]));
    if (layout.columns && mode != kModeNeighbours) return Corrupt("lossless colors: columns without neighbours");
  }
  const std::span<const uint8_t> coded = payload.subspan(pos);
  if (count / kMaxColorsPerByte > coded.size() + 8) return Corrupt("lossless colors: more colors than the bytes can hold");
  if (mode == kModeNeighbours && morton.size() != count) {
    // Only leaf-mode colors are coded from neighbours: anywhere else the section is not what the
    // geometry says it is.
    return Corrupt("lossless colors predicted from neighbours, but there are no voxels' Morton codes for them");
  }
  std::vector<Rgb8> colors(count);
  const std::span<const uint64_t> codes = mode == kModeNeighbours ? morton : std::span<const uint64_t>{};
  const bool exact = payload[0] == 2 ? DecodeGammaResiduals(coded, colors, codes) : DecodeMixed(coded, colors, codes, layout.columns);
  if (!exact) return Corrupt("lossless colors: the stream does not end where its colors do");
  for (Rgb8& c : colors) c = Restore(c, layout.order);
  return colors;
}

}  // namespace pointdag
