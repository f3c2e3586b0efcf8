// Block color stream version 4 (leaf mode; proto/PDAG_FORMAT.md §3): each bit of a weight's bit tree
// is coded with a logistic mix (entropy/logistic.h, as the geometry's mask mixer) of four models
// instead of version 3's one. Each model is chosen by the width and the bit tree's node, and by:
//   1. version 3's context: the decoded neighbours' mean position on the block's segment in weight
//      steps (0..15), else 16 + the previous weight of the block, and 33 + the position where the
//      neighbours are the cells two away (none of the 26 around precedes: 30 % of guanyin's
//      weights, 3-6 % of lion's and autzen's);
//   2. that position in half steps (0..30), else 31 + the previous weight, 48 + the position two
//      away: whether the neighbours' mean lies near a step or between two;
//   3. the previous weight of the block (0..16, 16 = the first): version 2's context;
//   4. the position in steps and how the previous weight relates to it (first, equal, below,
//      above), else 64 + the previous weight, 81 + those two away.
// The mixer learns a weight per model (and a bias) for each width and depth in the bit tree.
// Measured on the blocks of lion 1 cm, guanyin 2 mm and autzen 4 ft at 34 and 42 dB: weight bits
// 2-15 % below version 3's (most at low rates); one model alone as version 3 but learning fast while
// young 0.3-2 %; a fifth model (the two previous weights, the neighbours' spread, the face
// neighbours' own steps, or steps extrapolated from two voxels per axis) at most 1 % more. The
// cells two away where none of the 26 precedes: guanyin's weights 4-5 % fewer bits, lion's and
// autzen's 0.3-0.9 %.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "pointdag/color/block_fit.h"
#include "pointdag/color/weight_context.h"
#include "pointdag/entropy/binary_range_coder.h"
#include "pointdag/entropy/logistic.h"

namespace pointdag {

class WeightMixer {
 public:
  // A weight's contexts: where its neighbours lie, and the previous weight of its block (16 at the first).
  struct Context {
    NeighbourPosition near;
    uint32_t prev;
  };

  void Encode(BinaryRangeEncoder& rc, int bits, const Context& c, uint32_t w) {
    Code(bits, c, [&](int i, FixedP0 p) {
      const int bit = static_cast<int>(w >> i & 1);
      rc.Encode(p, bit);
      return bit;
    });
  }
  uint32_t Decode(BinaryRangeDecoder& rc, int bits, const Context& c) {
    return Code(bits, c, [&](int, FixedP0 p) { return rc.Decode(p); });
  }

 private:
  static constexpr int kInputs = 4;
  static constexpr int kStepContexts = 49, kHalfContexts = 79, kPreviousContexts = 17, kRelationContexts = 145;
  static constexpr int32_t kBias = 256;
  static constexpr int32_t kMaxWeight = 1 << 22;
  // The first model starts trusted alone at 1, the others at 0.3 (the bias at 0), as the mask mixer's.
  static constexpr std::array<int32_t, kInputs + 1> kInitialWeights = {65536, 19661, 19661, 19661, 0};

  // Codes one weight of `bits` bits (1..4), most significant first: code(i, p) codes bit i with P(0) = p.
  template <typename CodeBit>
  uint32_t Code(int bits, const Context& c, CodeBit&& code) {
    switch (bits) {
      case 1: return CodeWidth<1>(c, code);
      case 2: return CodeWidth<2>(c, code);
      case 3: return CodeWidth<3>(c, code);
      default: return CodeWidth<4>(c, code);
    }
  }
  // The width a constant: the bit tree's loop unrolls and the rows' offsets fold. With Stretch and
  // Train below: the mixer and range decoder of a lion 1 cm decode at 38 dB 362 -> 316 M instructions.
  template <int kBits, typename CodeBit>
  uint32_t CodeWidth(const Context& c, CodeBit& code) {
    const uint32_t prev = c.prev;
    const uint32_t step = c.near.step;
    const uint32_t relation = prev == 16 ? 0 : prev == step ? 1 : prev < step ? 2 : 3;
    const bool near = c.near.found && !c.near.far, far = c.near.far;
    const std::array<uint32_t, kInputs> rows = {
        static_cast<uint32_t>(kBits * kStepContexts) + (near ? step : far ? 33 + step : 16 + prev),
        static_cast<uint32_t>(kBits * kHalfContexts) + (near ? c.near.half_step : far ? 48 + c.near.half_step : 31 + prev),
        static_cast<uint32_t>(kBits * kPreviousContexts) + prev,
        static_cast<uint32_t>(kBits * kRelationContexts) + (near ? step * 4 + relation : far ? 81 + step * 4 + relation : 64 + prev),
    };
    uint32_t node = 1;
#pragma GCC unroll 4
    for (int i = kBits - 1; i >= 0; --i) {
      std::array<YoungBitModel*, kInputs> m = {&models_->step[rows[0]][node], &models_->half[rows[1]][node],
                                               &models_->previous[rows[2]][node], &models_->relation[rows[3]][node]};
      std::array<int32_t, kInputs + 1> s;
      for (int k = 0; k < kInputs; ++k) s[k] = Stretch(*m[k]);
      s[kInputs] = kBias;
      std::array<int32_t, kInputs + 1>& w = weights_[kBits][kBits - 1 - i];
      int64_t dot = 0;
      for (int k = 0; k <= kInputs; ++k) dot += int64_t{w[k]} * s[k];
      const int32_t p1 = kSquashTable[static_cast<size_t>(std::clamp<int64_t>(dot >> 16, -2047, 2047) + 2047)];
      const int bit = code(i, FixedP0{static_cast<uint32_t>(4096 - p1)});
      const int32_t err = (bit << 12) - p1;
      for (int k = 0; k <= kInputs; ++k) w[k] = Train(w[k], s[k], err);
      for (YoungBitModel* model : m) model->Update(bit);
      node = node << 1 | static_cast<uint32_t>(bit);
    }
    return node - (1u << kBits);
  }

  // kStretch[4096 - P0] of a model straight from the sum of its two estimates (P0 is that sum >> 5, | 1).
  static constexpr auto kStretchOfSum = [] {
    std::array<int16_t, 4096> t{};
    for (uint32_t x = 0; x < 4096; ++x) t[x] = kStretch[4096 - (x | 1)];
    return t;
  }();
  static int32_t Stretch(const YoungBitModel& m) { return kStretchOfSum[(uint32_t{m.fast} + m.slow) >> 5]; }
  // std::clamp(w + (s * err >> 11), -kMaxWeight, kMaxWeight), with one rarely taken test for both bounds.
  static int32_t Train(int32_t w, int32_t s, int32_t err) {
    const int32_t v = w + ((s * err) >> 11);
    if (static_cast<uint32_t>(v + kMaxWeight) > uint32_t{2 * kMaxWeight}) [[unlikely]] return v < 0 ? -kMaxWeight : kMaxWeight;
    return v;
  }

  template <int kContexts>
  using Rows = std::array<std::array<YoungBitModel, 1 << kMaxWeightBits>, (kMaxWeightBits + 1) * kContexts>;
  struct Models {
    Rows<kStepContexts> step{};
    Rows<kHalfContexts> half{};
    Rows<kPreviousContexts> previous{};
    Rows<kRelationContexts> relation{};
  };
  std::unique_ptr<Models> models_ = std::make_unique<Models>();
  // Per width and depth in the bit tree.
  std::array<std::array<std::array<int32_t, kInputs + 1>, kMaxWeightBits>, kMaxWeightBits + 1> weights_ = [] {
    std::array<std::array<std::array<int32_t, kInputs + 1>, kMaxWeightBits>, kMaxWeightBits + 1> t{};
    for (auto& width : t) width.fill(kInitialWeights);
    return t;
  }();
};

}  // namespace pointdag
