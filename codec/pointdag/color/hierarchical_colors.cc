#include "pointdag/color/hierarchical_colors.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <optional>
#include <type_traits>

#include "pointdag/color/hierarchical_models.h"
#include "pointdag/color/hierarchical_neighbours.h"
#include "pointdag/color/hierarchical_octree.h"
#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/entropy/binary_range_coder.h"
#include "pointdag/entropy/varint.h"

namespace pointdag {
namespace {

using hierarchical::Activity;
using hierarchical::Butterfly;
using hierarchical::ChromaFit;
using hierarchical::DivRound;
using hierarchical::FlagContext;
using hierarchical::kChildSide;
using hierarchical::kEarlierCells;
using hierarchical::kOffsets;
using hierarchical::kParentSide;
using hierarchical::kParentSideCells;
using hierarchical::kParentWeight;
using hierarchical::MagnitudeBucket;
using hierarchical::Models;
using hierarchical::Octree;
using hierarchical::OctreeLevel;
using hierarchical::Offset;
using hierarchical::OffsetIndex;
using hierarchical::Predictor;
using hierarchical::Ycc;

constexpr uint32_t kMaxMagnitude = uint32_t{1} << 24;
constexpr double kRounding = 0.43;      // quantizer offset below 0.5: a dead zone around 0
constexpr double kRdoLambda = 0.115;    // λ of the ±1 → 0 decision, in squared steps per bit
constexpr int kMaxSearchEncodes = 6;  // the benchmark scans take 2-3; a flat curve's best passing step is kept

struct Header {
  uint64_t count = 0;
  HierarchicalSteps steps;
  Ycc root{};
};

// The encoder's side of the shared walk: the true colors' sums per node, and the quantizer.
class EncoderSide {
 public:
  static constexpr bool kEncode = true;
  std::vector<std::vector<std::array<double, 3>>> sums;  // per level and node: Σ YCbCr (1/64) of its voxels
  BinaryRangeEncoder rc;

  template <typename Model>
  int Bit(Model& m, int bit) {
    rc.Encode(m, bit);
    return bit;
  }
  uint32_t Gamma(GammaModel& m, uint32_t v) {
    EncodeGamma(rc, m, v);
    return v;
  }
  // Dead-zone quantization, then ±1 → 0 where the bits saved outweigh the error added.
  // `greater_one`: the "> 1" flag's P0, asked for only where it matters.
  template <typename GreaterOne>
  static int32_t Quantize(double residual, int64_t step, FixedP0 zero, GreaterOne greater_one) {
    const double u = std::fabs(residual) / static_cast<double>(step);
    int32_t m = static_cast<int32_t>(std::min(std::floor(u + kRounding), static_cast<double>(kMaxMagnitude)));
    if (m == 1) {
      const double p_nonzero = zero.P0() / 4096.0, p_one = greater_one().P0() / 4096.0;
      const double bits_zero = -std::log2(1 - p_nonzero);
      const double bits_one = -std::log2(p_nonzero) - std::log2(p_one) + 1;
      if (u * u + kRdoLambda * bits_zero < (u - 1) * (u - 1) + kRdoLambda * bits_one) m = 0;
    }
    return residual < 0 ? -m : m;
  }
};

class DecoderSide {
 public:
  static constexpr bool kEncode = false;
  explicit DecoderSide(std::span<const uint8_t> in) : rc(in) {}
  BinaryRangeDecoder rc;

  template <typename Model>
  int Bit(Model& m, int) {
    return rc.Decode(m);
  }
  uint32_t Gamma(GammaModel& m, uint32_t) { return DecodeGamma(rc, m); }
};

// Codes (EncoderSide) or decodes (DecoderSide) every level's differences, top down, nodes in Morton
// order, a node's butterflies coarsest first, each Y, Cb, Cr; -> the voxels' reconstructed means.
template <typename Side>
StatusOr<std::vector<Ycc>> CodeLevels(const Octree& tree, const Header& header, Side& side) {
  auto models = std::make_unique<Models>();
  std::vector<Ycc> rec = {header.root}, child_rec;
  std::vector<uint8_t> nz = {0}, child_nz;  // per node: its parent's nonzero values per channel, 2 bits each, capped at 2
  std::array<ChromaFit, 3> fit;
  for (int l = 0; l < tree.depth; ++l) {
    const OctreeLevel& nodes = tree.level[l];
    const OctreeLevel& children = tree.level[l + 1];
    const int height = tree.depth - 1 - l;
    const int64_t luma_step = hierarchical::LevelStep(header.steps.luma, height);
    const int64_t chroma_step = hierarchical::LevelStep(header.steps.chroma, height);
    const int hctx = std::min(height, 3);
    child_rec.assign(children.code.size(), Ycc{});
    child_nz.assign(children.code.size(), 0);
    const hierarchical::LevelIndex index(nodes.code);
    std::vector<uint8_t> own_nz(nodes.code.size(), 0);  // per node: its nonzero values, all channels
    std::vector<std::array<uint8_t, 3>> own_magnitude(nodes.code.size());  // per node and channel: Σ |value|, capped at 255
    for (size_t i = 0; i < nodes.code.size(); ++i) {
      const uint32_t first = nodes.first_child[i], end = nodes.first_child[i + 1];
      if (end - first == 1) {  // a lone child: the parent's mean, nothing coded
        child_rec[first] = rec[i];
        continue;
      }
      std::array<int64_t, 27> neighbour;
      neighbour.fill(-1);
      uint32_t any_order = 0, earlier = 0;
      for (uint8_t mask = nodes.child_mask[i], s = 0; s < 8; ++s) {
        if ((mask >> s) & 1) any_order |= kParentSideCells[s], earlier |= kEarlierCells[s];
      }
      for (const Offset& o : kOffsets) {
        const int x = OffsetIndex(o.d[0], o.d[1], o.d[2]);
        if (!(((any_order | earlier) >> x) & 1)) continue;
        uint64_t cell = nodes.code[i];
        bool inside = true;
        for (int a = 0; a < 3 && inside; ++a) {
          if (o.d[a] != 0) inside = hierarchical::StepCell(cell, a, o.d[a], l, cell);
        }
        // A cell after the node in the level's order is read only as a parent-side predictor.
        if (inside && (cell < nodes.code[i] || ((any_order >> x) & 1))) neighbour[x] = index.Find(cell);
      }
      int near_nz = 0;  // the decoded face neighbours' nonzero values: 0, 1-2, 3+
      std::array<uint32_t, 3> near_magnitude = {0, 0, 0};  // and their Σ |value| per channel
      for (const Offset& o : kOffsets) {
        const int64_t n = neighbour[OffsetIndex(o.d[0], o.d[1], o.d[2])];
        if (o.nonzero == 1 && n >= 0 && n < static_cast<int64_t>(i)) {
          near_nz += own_nz[n];
          for (int c = 0; c < 3; ++c) near_magnitude[c] += own_magnitude[n][c];
        }
      }
      near_nz = near_nz == 0 ? 0 : (near_nz <= 2 ? 1 : 2);
      std::array<int64_t, 3> lo, hi;
      for (int c = 0; c < 3; ++c) lo[c] = hi[c] = rec[i][c];
      const auto seen = [&](const Ycc& v) {
        for (int c = 0; c < 3; ++c) lo[c] = std::min<int64_t>(lo[c], v[c]), hi[c] = std::max<int64_t>(hi[c], v[c]);
      };
      std::array<uint32_t, 8> weight{};
      std::array<std::array<int64_t, 3>, 8> prediction{};
      for (uint32_t j = first; j < end; ++j) weight[children.code[j] & 7] = children.weight[j];
      for (uint32_t j = first; j < end; ++j) {
        const int slot = static_cast<int>(children.code[j] & 7);
        std::array<int64_t, 3> acc;
        for (int c = 0; c < 3; ++c) acc[c] = kParentWeight * rec[i][c];
        int64_t total = kParentWeight;
        const auto add = [&](const Ycc& v, int64_t w) {
          for (int c = 0; c < 3; ++c) acc[c] += w * v[c];
          total += w;
          seen(v);
        };
        for (const Predictor& p : kParentSide[slot]) {
          const int64_t n = neighbour[p.up];
          if (n >= 0) add(rec[n], p.weight);
        }
        for (const Predictor& p : kChildSide[slot]) {  // decoded where their parent came first
          const int64_t n = neighbour[p.up];
          if (n < 0 || n >= static_cast<int64_t>(i)) continue;
          const uint8_t mask = nodes.child_mask[n];
          if (!((mask >> p.slot) & 1)) continue;
          add(child_rec[nodes.first_child[n] + std::popcount(static_cast<unsigned>(mask & ((1u << p.slot) - 1)))], p.weight);
        }
        for (int c = 0; c < 3; ++c) prediction[slot][c] = DivRound(acc[c], total);
      }
      const hierarchical::NodePlan plan = hierarchical::PlanNode(nodes.child_mask[i], weight);
      std::array<int64_t, 8> weights64;
      for (int s = 0; s < 8; ++s) weights64[s] = weight[s];
      std::array<std::array<int64_t, 7>, 3> predicted{}, decoded{};
      std::array<std::array<double, 7>, 3> truth{};
      for (int c = 0; c < 3; ++c) {
        std::array<int64_t, 8> means{};
        for (int s = 0; s < 8; ++s) means[s] = prediction[s][c];
        hierarchical::ForwardDifferences(plan, means, weights64, predicted[c], DivRound);
        if constexpr (Side::kEncode) {
          std::array<double, 8> true_means{}, true_weights{};
          for (uint32_t j = first; j < end; ++j) {
            true_weights[children.code[j] & 7] = children.weight[j];
            true_means[children.code[j] & 7] = side.sums[l + 1][j][c] / children.weight[j];
          }
          hierarchical::ForwardDifferences(plan, true_means, true_weights, truth[c],
                                           [](double sum, double w) { return sum / w; });
        }
      }
      std::array<std::array<int64_t, 2>, 7> step;  // per butterfly: luma's, chroma's
      for (int k = 0; k < plan.count; ++k) {
        const Butterfly& bf = plan.butterfly[k];
        step[k] = {hierarchical::DifferenceStep(luma_step, bf.wa, bf.wb),
                   hierarchical::DifferenceStep(chroma_step, bf.wa, bf.wb)};
      }
      std::array<std::array<int32_t, 7>, 3> value{};
      std::array<int, 3> local = {0, 0, 0}, magnitudes = {0, 0, 0};
      int32_t last_luma = 0;  // the node's last nonzero luma value so far
      for (int k = plan.count - 1; k >= 0; --k) {
        for (int c = 0; c < 3; ++c) {
          const int64_t st = step[k][c == 0 ? 0 : 1];
          const int parent_nz = (nz[i] >> (2 * c)) & 3;
          const int luma_nz = value[0][k] != 0;
          const int local_ctx = c == 0 ? std::min(local[0], 2) : (c == 1 ? luma_nz : std::min(luma_nz + 2 * (value[1][k] != 0), 2));
          const int64_t from_luma = c > 0 ? DivRound(fit[c].Alpha() * value[0][k] * step[k][0], 4096) : 0;
          const int act = Activity(hi[c] - lo[c], st);
          const FlagContext flag{c, act, hctx, std::min(height, 9), plan.butterfly[k].stage, parent_nz, local_ctx, near_nz,
                                 MagnitudeBucket(static_cast<uint64_t>(4 * std::abs(predicted[c][k]) / st)),
                                 MagnitudeBucket(near_magnitude[c])};
          FixedP0 zero = models->zero.Mix(flag);
          int32_t v = 0;
          if constexpr (Side::kEncode) {
            v = EncoderSide::Quantize(truth[c][k] - static_cast<double>(predicted[c][k] + from_luma), st, zero,
                                      [&] { return models->greater_one.Mix(flag); });
          }
          const int is_zero = side.Bit(zero, v == 0);
          models->zero.Update(is_zero);
          if (!is_zero) {
            uint32_t magnitude = 1;
            FixedP0 greater_one = models->greater_one.Mix(flag);
            const int big = side.Bit(greater_one, std::abs(v) > 1);
            models->greater_one.Update(big);
            if (big) {
              magnitude = 1 + side.Gamma(models->magnitude[c][act], static_cast<uint32_t>(std::abs(v) - 1));
              if (magnitude > kMaxMagnitude || magnitude < 2) return Corrupt("hierarchical colors: a coefficient is out of range");
            }
            const int64_t p = predicted[c][k];
            const int predicted_sign = 4 * std::abs(p) < st ? 0 : (p > 0 ? 1 : 2);
            // Luma's sign by the node's previous nonzero luma value's (a missed edge tilts them alike),
            // chroma's by this butterfly's luma value's.
            const int32_t reference = c == 0 ? last_luma : value[0][k];
            const int luma_sign = reference > 0 ? 1 : (reference < 0 ? 2 : 0);
            const bool negative = side.Bit(models->sign[c][predicted_sign][luma_sign], v < 0);
            v = negative ? -static_cast<int32_t>(magnitude) : static_cast<int32_t>(magnitude);
          } else {
            v = 0;
          }
          value[c][k] = v;
          local[c] += v != 0;
          magnitudes[c] += std::abs(v);
          const int64_t coded = from_luma + int64_t{v} * st;
          decoded[c][k] = std::clamp(predicted[c][k] + coded, -hierarchical::kDifferenceLimit, hierarchical::kDifferenceLimit);
          if (c > 0 && value[0][k] != 0) fit[c].Add(value[0][k], coded, step[k][0]);
          if (c == 0 && v != 0) last_luma = v;
        }
      }
      const uint8_t packed = static_cast<uint8_t>(std::min(local[0], 2) | std::min(local[1], 2) << 2 | std::min(local[2], 2) << 4);
      for (int c = 0; c < 3; ++c) {
        std::array<int64_t, 8> means{};
        hierarchical::InverseMeans(plan, rec[i][c], std::span<const int64_t>(decoded[c].data(), plan.count), means);
        for (uint32_t j = first; j < end; ++j) child_rec[j][c] = static_cast<int32_t>(means[children.code[j] & 7]);
      }
      for (uint32_t j = first; j < end; ++j) child_nz[j] = packed;
      own_nz[i] = static_cast<uint8_t>(local[0] + local[1] + local[2]);
      for (int c = 0; c < 3; ++c) own_magnitude[i][c] = static_cast<uint8_t>(std::min(magnitudes[c], 255));
    }
    rec.swap(child_rec);
    nz.swap(child_nz);
  }
  return rec;
}

void PutU16(std::vector<uint8_t>& out, uint16_t v) { out.insert(out.end(), {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)}); }

std::vector<Rgb8> ToRgb(const std::vector<Ycc>& voxels) {
  std::vector<Rgb8> out(voxels.size());
  for (size_t i = 0; i < voxels.size(); ++i) out[i] = hierarchical::YccToRgb(voxels[i]);
  return out;
}

// The octree and the true colors' sums, built once for every encode of a search.
class HierarchicalEncoder {
 public:
  static StatusOr<HierarchicalEncoder> Create(std::span<const Rgb8> colors, std::span<const uint64_t> morton) {
    if (colors.size() != morton.size()) return InvalidArgument("hierarchical colors need one Morton code per color (leaf mode)");
    HierarchicalEncoder e;
    ASSIGN_OR_RETURN(e.tree_, hierarchical::BuildOctree(morton));
    e.colors_ = colors;
    auto& sums = e.sums_;
    sums.resize(e.tree_.depth + 1);
    sums[e.tree_.depth].resize(colors.size());
    for (size_t i = 0; i < colors.size(); ++i) sums[e.tree_.depth][i] = hierarchical::RgbToYcc(colors[i]);
    for (int l = e.tree_.depth - 1; l >= 0; --l) {
      const OctreeLevel& level = e.tree_.level[l];
      sums[l].assign(level.code.size(), {0, 0, 0});
      for (size_t i = 0; i < level.code.size(); ++i) {
        for (uint32_t j = level.first_child[i]; j < level.first_child[i + 1]; ++j) {
          for (int c = 0; c < 3; ++c) sums[l][i][c] += sums[l + 1][j][c];
        }
      }
    }
    return e;
  }

  StatusOr<HierarchicalColors> Encode(HierarchicalSteps steps) {
    if (steps.luma == 0 || steps.chroma == 0) return InvalidArgument("hierarchical color steps must be at least 1/16");
    Header header{colors_.size(), steps, {}};
    const double voxels = static_cast<double>(colors_.size());
    header.root = {static_cast<int32_t>(std::lround(sums_[0][0][0] / voxels)),
                   static_cast<int32_t>(std::lround(sums_[0][0][1] / voxels)),
                   static_cast<int32_t>(std::lround(sums_[0][0][2] / voxels))};
    EncoderSide side;
    side.sums = std::move(sums_);
    StatusOr<std::vector<Ycc>> voxels_rec = CodeLevels(tree_, header, side);
    sums_ = std::move(side.sums);
    if (!voxels_rec.ok()) return voxels_rec.status();
    HierarchicalColors out;
    out.steps = steps;
    out.payload.push_back(kHierarchicalVersion);
    PutVarint(out.payload, header.count);
    PutU16(out.payload, steps.luma);
    PutU16(out.payload, steps.chroma);
    for (int32_t v : header.root) PutU16(out.payload, static_cast<uint16_t>(static_cast<int16_t>(v)));
    const std::vector<uint8_t> coded = side.rc.Finish();
    out.payload.insert(out.payload.end(), coded.begin(), coded.end());
    out.decoded = ToRgb(*voxels_rec);
    return out;
  }

  std::span<const Rgb8> colors() const { return colors_; }

 private:
  Octree tree_;
  std::span<const Rgb8> colors_;
  std::vector<std::vector<std::array<double, 3>>> sums_;
};

// Chroma's step over luma's: PSNR-Y ignores chroma, so coarser chroma is free bits, up to where
// PSNR-RGB would fall below VBR's at the same PSNR-Y (docs/benchmarks.md): 1.5 up to 36 dB, rising
// to 2 at 42 dB, where the scans' PSNR-RGB has more room.
double ChromaStepRatio(double target_psnr_y) { return std::clamp(1.5 + (target_psnr_y - 36) / 12, 1.5, 2.0); }

HierarchicalSteps StepsFor(double luma16, double chroma_ratio) {
  const auto to16 = [](double v) { return static_cast<uint16_t>(std::clamp(std::lround(v), 1L, 65535L)); };
  return {to16(luma16), to16(luma16 * chroma_ratio)};
}

}  // namespace

StatusOr<HierarchicalColors> EncodeHierarchicalColors(std::span<const Rgb8> colors, std::span<const uint64_t> morton,
                                                      HierarchicalSteps steps) {
  ASSIGN_OR_RETURN(HierarchicalEncoder encoder, HierarchicalEncoder::Create(colors, morton));
  return encoder.Encode(steps);
}

StatusOr<HierarchicalColors> EncodeHierarchicalColorsForTarget(std::span<const Rgb8> colors,
                                                               std::span<const uint64_t> morton, double target_psnr_y,
                                                               uint32_t start) {
  if (!std::isfinite(target_psnr_y) || target_psnr_y <= 0) return InvalidArgument("target PSNR must be a positive number of dB");
  ASSIGN_OR_RETURN(HierarchicalEncoder encoder, HierarchicalEncoder::Create(colors, morton));
  // A uniform quantizer's error is step²/12: the step that would give the target's MSE, a bit
  // coarser because the dead zone's zeros and the prediction leave many values untouched.
  const double mse = 255.0 * 255.0 / std::pow(10.0, target_psnr_y / 10.0);
  double step = start > 0 ? start : 16 * 1.1 * std::sqrt(12 * mse);
  std::optional<HierarchicalColors> best;  // the largest step found to meet the target
  double pass_step = 0, fail_step = 0;      // the bracket (0: not found yet)
  size_t fail_bytes = 0;
  int encodes = 0;
  double last_step = 0, last_margin = 0;
  for (int round = 0; round < kMaxSearchEncodes; ++round) {
    const HierarchicalSteps steps = StepsFor(step, ChromaStepRatio(target_psnr_y));
    ASSIGN_OR_RETURN(HierarchicalColors trial, encoder.Encode(steps));
    ++encodes;
    const double margin = MeasureColorPsnr(colors, trial.decoded).y - target_psnr_y;
    const double tried = steps.luma;
    if (margin >= 0) {
      if (tried > pass_step) pass_step = tried, best = std::move(trial);
      if (margin < 0.05) break;
    } else if (fail_step == 0 || tried < fail_step) {
      fail_step = tried, fail_bytes = trial.payload.size();
    }
    // Near the target, where the rate no longer follows the step: within 1 % of the bracket's bytes.
    if (best && fail_step > 0 && best->payload.size() <= fail_bytes + fail_bytes / 100) break;
    if (fail_step > 0 && fail_step <= 1) break;
    if (pass_step > 0 && fail_step > 0 && fail_step - pass_step <= std::max(1.0, 0.02 * pass_step)) break;
    if (pass_step >= 65535) break;
    // Secant on (log step, PSNR) towards the target plus a little; ~5 dB per doubling to start.
    double slope = -5.0 / std::log(2.0);
    bool flat = false;  // PSNR-Y moved less than 1 dB per doubling of the step
    if (last_step > 0 && last_step != tried) {
      const double s = (margin - last_margin) / (std::log(tried) - std::log(last_step));
      if (s < -0.5) slope = s;
      flat = s > -1.0 / std::log(2.0);
    }
    double next = std::exp(std::log(tried) + (0.02 - margin) / slope);
    // Colors the prediction gets nearly right stay far from the target whatever the step (a smooth
    // gradient): until it is bracketed, such a curve is crossed in strides of 8×.
    if (flat && fail_step == 0) next = std::max(next, tried * 8);
    if (flat && pass_step == 0) next = std::min(next, tried / 8);
    const double lo = pass_step > 0 ? pass_step : 1, hi = fail_step > 0 ? fail_step : 65535;
    if (!(next > lo && next < hi)) next = pass_step > 0 && fail_step > 0 ? std::sqrt(lo * hi) : std::clamp(next, lo, hi);
    last_step = tried, last_margin = margin;
    if (std::lround(next) == std::lround(tried)) break;
    step = next;
  }
  if (!best) {
    return InvalidArgument("hierarchical colors cannot reach " + std::to_string(target_psnr_y) + " dB PSNR-Y on these colors");
  }
  best->encodes = encodes;
  return std::move(*best);
}

StatusOr<std::vector<Rgb8>> DecodeHierarchicalColors(std::span<const uint8_t> payload, uint64_t count,
                                                     std::span<const uint64_t> morton) {
  if (morton.size() != count) return Corrupt("hierarchical colors need the voxels' Morton codes (one color per voxel)");
  size_t pos = 0;
  if (payload.empty()) return Truncated("hierarchical colors: no header");
  if (payload[pos++] != kHierarchicalVersion) return Unsupported("hierarchical colors of version " + std::to_string(payload[0]));
  Header header;
  if (!GetVarint(payload, pos, header.count)) return Truncated("hierarchical colors: header truncated");
  if (header.count != count) return Corrupt("hierarchical colors hold a different number of colors than the geometry's voxels");
  if (payload.size() < pos + 10) return Truncated("hierarchical colors: header truncated");
  const auto u16 = [&] {
    const uint16_t v = static_cast<uint16_t>(payload[pos] | payload[pos + 1] << 8);
    pos += 2;
    return v;
  };
  header.steps.luma = u16();
  header.steps.chroma = u16();
  for (int32_t& v : header.root) v = static_cast<int16_t>(u16());
  if (header.steps.luma == 0 || header.steps.chroma == 0) return Corrupt("hierarchical colors: a step of 0");
  ASSIGN_OR_RETURN(const Octree tree, hierarchical::BuildOctree(morton));
  DecoderSide side(payload.subspan(pos));
  ASSIGN_OR_RETURN(const std::vector<Ycc> voxels, CodeLevels(tree, header, side));
  if (!side.rc.consumed_exactly()) return Corrupt("hierarchical colors: the coded stream is truncated or has trailing bytes");
  return ToRgb(voxels);
}

}  // namespace pointdag
