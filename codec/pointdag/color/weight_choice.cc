#include "pointdag/color/weight_choice.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace pointdag {
namespace {

// Estimated bits of weight w after weight `prev` of the same block, in 1/16ths, less those of
// w = prev: by |w - prev| and the width, the mean coded cost of the weights at each distance less
// that at distance 0, measured in stream version 3 (whose context is the neighbours' colors, not
// the previous weight: the costs are about half of version 2's) on lion, guanyin and autzen at 34
// and 42 dB with this choice on, made non-decreasing.
constexpr std::array<std::array<uint8_t, 16>, kMaxWeightBits + 1> kDistanceCost = {{
    {},
    {0, 16},
    {0, 25, 41, 46},
    {0, 15, 29, 39, 45, 48, 48, 48},
    {0, 7, 15, 22, 29, 35, 39, 41, 42, 44, 44, 44, 44, 44, 44, 44},
}};

// A priced block of kBits per weight: the Viterbi search below, the width a constant so that the
// palette divides by a constant. `ends` by value: the stores to `out` may not alias it, so that its
// axis is computed once, not once per color.
template <int kBits>
uint64_t ChooseWeights(std::span<const Rgb8> block, const Endpoints ends, uint32_t price, std::span<uint8_t> out) {
  constexpr int kTop = (1 << kBits) - 1;
  for (size_t i = 0; i < block.size(); ++i) out[i] = static_cast<uint8_t>(ChooseWeight(block[i], ends, kBits));
  // Viterbi over each color's error-minimizing weight and its two neighbours (wider choices moved
  // nothing on lion, guanyin and autzen).
  std::array<Rgb8, kTop + 1> palette;
  for (int w = 0; w <= kTop; ++w) palette[w] = Interpolate(ends, static_cast<uint32_t>(w), kBits);
  // The price of a step from the previous weight to this one, by their difference d + kTop + 2 (d
  // within -kTop - 2..kTop + 2: a choice outside 0..kTop is one beyond, and costs kFar anyway).
  std::array<uint64_t, 2 * kTop + 5> step_cost{};
  for (int d = -kTop - 2; d <= kTop + 2; ++d) step_cost[d + kTop + 2] = uint64_t{price} * kDistanceCost[kBits][std::min(std::abs(d), kTop)];
  // A choice outside 0..kTop costs kFar: above any real cost (under 2^52), so never the least.
  constexpr uint64_t kFar = uint64_t{1} << 62;
  // Per color, each choice's best previous choice (2 bits each), reused across calls: no allocation per block.
  thread_local std::vector<uint8_t> from;
  from.resize(block.size());
  std::array<uint64_t, 3> cost{}, next{};
  for (size_t i = 0; i < block.size(); ++i) {
    const int lowest = out[i] - 1;  // choice s is weight lowest + s
    // Choice t of the previous color to choice s is a step of (out[i] - out[i - 1]) + s - t: the
    // costs of s - t = -2..2 from move[0]. The first weight costs the same whatever it is.
    static constexpr std::array<uint64_t, 5> kFirst{};
    const uint64_t* move = i > 0 ? &step_cost[static_cast<size_t>(out[i] - out[i - 1] + kTop)] : kFirst.data();
    uint8_t links = 0;
    for (int s = 0; s < 3; ++s) {
      const int w = lowest + s;
      if (w < 0 || w > kTop) {
        next[s] = kFar;
        continue;
      }
      uint64_t least = cost[0] + move[s + 2];
      int best = 0;
      if (const uint64_t c = cost[1] + move[s + 1]; c < least) least = c, best = 1;
      if (const uint64_t c = cost[2] + move[s]; c < least) least = c, best = 2;
      next[s] = least + uint64_t{16} * BlockError(block[i], palette[w]);
      links |= static_cast<uint8_t>(best << (2 * s));
    }
    from[i] = links;
    cost = next;
  }
  int s = static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  for (size_t i = block.size(); i-- > 0;) {
    const int previous = from[i] >> (2 * s) & 3;
    out[i] = static_cast<uint8_t>(out[i] - 1 + s);
    s = previous;
  }
  return *std::min_element(cost.begin(), cost.end());
}

}  // namespace

// 1.0 x a color's allowed error (BlockError 3072 max_mse, block_codec.cc) per bit: with the table
// above, lion, guanyin and autzen at 34-42 dB were smallest at equal PSNR-Y near 0.9-1.0 (a flat
// optimum: 0.5-1.4 within ~0.5 %).
uint32_t WeightRatePrice(double max_mse, size_t array_colors) {
  if (array_colors < kMacroBlockColors || !(max_mse > 0)) return 0;
  return static_cast<uint32_t>(std::min(max_mse * 3072.0, 4e9));
}

uint64_t ChooseBlockWeights(std::span<const Rgb8> colors, const ColorBlock& b, std::span<uint8_t> out) {
  const std::span<const Rgb8> block = colors.subspan(b.start, b.length);
  const Endpoints ends = b.ends;  // a local copy: the stores to `out` may not alias it, so its axis is computed once
  if (b.bits == 0 || b.rate_price == 0) {
    for (uint32_t i = 0; i < b.length; ++i) out[i] = static_cast<uint8_t>(ChooseWeight(block[i], ends, b.bits));
    return 0;
  }
  switch (b.bits) {
    case 1: return ChooseWeights<1>(block, ends, b.rate_price, out);
    case 2: return ChooseWeights<2>(block, ends, b.rate_price, out);
    case 3: return ChooseWeights<3>(block, ends, b.rate_price, out);
    default: return ChooseWeights<4>(block, ends, b.rate_price, out);
  }
}

// Least squares for fixed weights t = w / m: A and B minimize the summed squared error of
// (1 - t) A + t B in any metric (Q factors out of the normal equations), per channel a 2x2 system.
void RefitEnds(std::span<const Rgb8> colors, ColorBlock& b, std::span<uint8_t> weights) {
  if (b.bits == 0 || b.rate_price == 0 || b.length < 3) {
    ChooseBlockWeights(colors, b, weights);
    return;
  }
  const std::span<uint8_t> w = weights.first(b.length);
  const uint64_t before = ChooseBlockWeights(colors, b, w);
  const double m = (1 << b.bits) - 1;
  double aa = 0, ab = 0, bb = 0, x[3] = {}, y[3] = {};
  for (uint32_t i = 0; i < b.length; ++i) {
    const double t = w[i] / m, u = 1 - t;
    const Rgb8 c = colors[b.start + i];
    aa += u * u, ab += u * t, bb += t * t;
    const double ch[3] = {static_cast<double>(c.r), static_cast<double>(c.g), static_cast<double>(c.b)};
    for (int k = 0; k < 3; ++k) x[k] += u * ch[k], y[k] += t * ch[k];
  }
  const double det = aa * bb - ab * ab;
  if (!(det > 1e-9)) return;
  uint8_t na[3], nb[3];
  for (int k = 0; k < 3; ++k) {
    na[k] = static_cast<uint8_t>(std::clamp(std::lround((bb * x[k] - ab * y[k]) / det), 0l, 255l));
    nb[k] = static_cast<uint8_t>(std::clamp(std::lround((aa * y[k] - ab * x[k]) / det), 0l, 255l));
  }
  ColorBlock trial = b;
  trial.ends = {{na[0], na[1], na[2]}, {nb[0], nb[1], nb[2]}};
  if (trial.ends == b.ends) return;
  thread_local std::vector<uint8_t> trial_weights;
  trial_weights.resize(b.length);
  if (ChooseBlockWeights(colors, trial, trial_weights) < before) {
    b.ends = trial.ends;
    std::copy(trial_weights.begin(), trial_weights.end(), w.begin());
  }
}

}  // namespace pointdag
