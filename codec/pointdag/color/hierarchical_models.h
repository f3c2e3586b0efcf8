// The hierarchical colors' (hierarchical_colors.cc) adaptive models: the zero and "> 1" flags' logistic
// mixes of four context models each, the magnitudes' and signs' models, and chroma's fit to luma.
// Everything here is integer arithmetic that a decoder repeats bit for bit (proto/PDAG_FORMAT.md §3).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstdlib>

#include "pointdag/color/hierarchical_octree.h"
#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/entropy/binary_range_coder.h"
#include "pointdag/entropy/logistic.h"

namespace pointdag::hierarchical {

// A flag's logistic mix (entropy/logistic.h) of four models and a bias by two sets of weights, one
// chosen by channel, height (0..3) and local count (0..2), one by channel and activity (0..8), each
// learnt as it codes; the flag's logit is the mean of the two mixes'.
class FlagMixer {
 public:
  static constexpr int kModels = 4;
  static constexpr int kInputs = kModels + 1;  // the last: a constant (a bias the weights learn)
  // The bit's P0 in 1/4096 from the models' stretched probabilities; Update after the bit.
  FixedP0 Mix(std::array<YoungBitModel*, kModels> models, int c, int height, int local, int activity) {
    models_ = models;
    for (int k = 0; k < kModels; ++k) stretched_[k] = kStretch[4096 - models[k]->P0()];
    const int32_t d = (mixes_[0].Start(by_height_[c][height * 3 + local], stretched_) +
                       mixes_[1].Start(by_activity_[c][activity], stretched_)) >> 1;
    return FixedP0{static_cast<uint32_t>(4096 - kSquashTable[static_cast<size_t>(d + 2047)])};
  }
  void Update(int bit) {
    for (Mix1& m : mixes_) m.Update(bit, stretched_);
    for (YoungBitModel* m : models_) m->Update(bit);
  }

 private:
  using Weights = std::array<int32_t, kInputs>;
  // One set of weights in use: its logit d, and P(1) = squash(d) to learn from.
  struct Mix1 {
    Weights* w = nullptr;
    int32_t p1 = 2048;  // P(1) in 1/4096
    int32_t Start(Weights& weights, const std::array<int32_t, kInputs>& s) {
      w = &weights;
      int64_t dot = 0;
      for (int k = 0; k < kInputs; ++k) dot += int64_t{weights[k]} * s[k];
      const int32_t d = static_cast<int32_t>(std::clamp<int64_t>(dot >> 16, -2047, 2047));
      p1 = kSquashTable[static_cast<size_t>(d + 2047)];
      return d;
    }
    void Update(int bit, const std::array<int32_t, kInputs>& s) {
      const int32_t err = (bit << 12) - p1;
      for (int k = 0; k < kInputs; ++k) (*w)[k] = std::clamp((*w)[k] + ((s[k] * err) >> 10), -(1 << 22), 1 << 22);
    }
  };
  // Starting weights 0.4, 0.4, 0.3, 0.3 (in 1/65536): the mix starts a little above the models' mean;
  // the bias's 0.
  static constexpr Weights kStart = {26214, 26214, 19661, 19661, 0};
  template <size_t N>
  static std::array<std::array<Weights, N>, 3> Fresh() {
    std::array<std::array<Weights, N>, 3> t{};
    for (auto& channel : t) channel.fill(kStart);
    return t;
  }
  std::array<std::array<Weights, 12>, 3> by_height_ = Fresh<12>();
  std::array<std::array<Weights, 9>, 3> by_activity_ = Fresh<9>();
  std::array<Mix1, 2> mixes_{};
  std::array<YoungBitModel*, kModels> models_{};
  std::array<int32_t, kInputs> stretched_ = {0, 0, 0, 0, 256};  // the bias: one nat (256/256)
};

// 0, 1, 2-3, 4-7, 8+: bit_width capped at 4.
inline int MagnitudeBucket(uint64_t v) { return std::min(static_cast<int>(std::bit_width(v)), 4); }

// What a coefficient's flags are coded with, all known to the decoder before them.
struct FlagContext {
  int c;                 // channel
  int activity;          // 0..8
  int height;            // 0..3
  int height10;          // 0..9
  int stage;             // the butterfly's, 0..2
  int parent_nz;         // the parent's nonzero values in this channel, 0..2
  int local;             // this node's earlier nonzero values, 0..2 (hierarchical_colors.cc)
  int near_nz;           // the decoded face neighbours' nonzero values: 0, 1-2, 3+
  int prediction;        // MagnitudeBucket of the predicted difference in quarter steps
  int near_magnitude;    // MagnitudeBucket of the decoded face neighbours' Σ |value| in this channel
};

// The zero flag's and the "> 1" flag's models: each flag has its own four, mixed (FlagMixer).
struct FlagModels {
  YoungBitModel by_activity[3][9][4][3][3];  // channel, activity, height, parent's count, local count
  YoungBitModel by_stage[3][3][10][3][3];    // channel, stage, height10, parent's count, local count
  YoungBitModel by_neighbours[3][9][3];      // channel, activity, near_nz
  YoungBitModel by_prediction[3][4][5][5];   // channel, height, prediction, near_magnitude
  FlagMixer mixer;

  FixedP0 Mix(const FlagContext& x) {
    return mixer.Mix({&by_activity[x.c][x.activity][x.height][x.parent_nz][x.local],
                      &by_stage[x.c][x.stage][x.height10][x.parent_nz][x.local], &by_neighbours[x.c][x.activity][x.near_nz],
                      &by_prediction[x.c][x.height][x.prediction][x.near_magnitude]},
                     x.c, x.height, x.local, x.activity);
  }
  void Update(int bit) { mixer.Update(bit); }
};

struct Models {
  FlagModels zero, greater_one;
  GammaModel magnitude[3][9];  // channel, activity
  BitModel sign[3][3][3];      // channel, sign of the predicted difference, of a luma value (hierarchical_colors.cc)
};

// Chroma's value predicted from luma's at the same butterfly: a running least-squares slope.
struct ChromaFit {
  int64_t sxy = 0, sxx = 0;
  int64_t Alpha() const { return sxx == 0 ? 0 : std::clamp<int64_t>(DivRound(sxy * 4096, sxx), -8192, 8192); }
  void Add(int32_t luma_value, int64_t chroma_difference, int64_t luma_step) {
    const int64_t y = std::clamp<int64_t>(luma_value, -1024, 1024);
    const int64_t c = std::clamp<int64_t>(DivRound(chroma_difference * 256, luma_step), -(1 << 20), 1 << 20);
    sxy += y * c;
    sxx += y * y * 256;
    while (sxx > (int64_t{1} << 40) || std::abs(sxy) > (int64_t{1} << 40)) sxy >>= 1, sxx >>= 1;
  }
};

// How large a difference the neighbourhood's spread suggests, in steps: log2 buckets 0..8.
inline int Activity(int64_t spread, int64_t step) {
  const int64_t e = (spread << 8) / step;
  return e == 0 ? 0 : std::clamp(static_cast<int>(std::bit_width(static_cast<uint64_t>(e))) - 5, 0, 8);
}

}  // namespace pointdag::hierarchical
