// Geometry stream version 5's mask bits (proto/PDAG_FORMAT.md §2.2): version 4's mixer with two
// stronger models in place of its two weakest, and a secondary estimate of the mixed probability.
// - *pattern*: child c's face and edge neighbours on its own level that are already coded, one bit
//   each, and its three neighbours at −2 (spatial_context.h kPatternLayout), per class group: the
//   shape of the surface next to the child, where version 4 saw three of these bits and an any-of-four;
// - *side*: (child, any bit so far) × which of the 7 parent-level neighbours on the child's side exist
//   (faces, edges, corner; version 2's context keeps only "at least 2 of 4");
// - an APM (lpaq's adaptive probability map): the mixed probability refined by a table indexed by a
//   small context (child, lower neighbours, those at −2, outer and diagonal) and interpolated between
//   33 buckets of the mixer's stretched output, then averaged 3:1 with the mix.
// The mask-so-far and parent-mask models of versions 3 and 4 are gone: with the pattern beside them
// they were worth less than 0.1 %, and each costs a model per bit. Measured (docs/benchmarks.md): each
// of the five inputs is worth 0.4–1.7 % on the seven scans, the APM 0.4 %; a second mixer 0.3 % and a
// second APM 0.2 % more, for 21 % and 10 % more decode time, were not taken.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "pointdag/dag/mask_mixer.h"
#include "pointdag/dag/spatial_context.h"

namespace pointdag {

// Where each (class group, child) block of the pattern model starts: 2^(kPatternLayout.count[c] + 3) entries each.
constexpr auto kPatternBase = [] {
  std::array<std::array<uint32_t, 8>, 4> t{};
  uint32_t at = 0;
  for (int g = 0; g < 3; ++g) {
    for (int c = 0; c < 8; ++c) {
      t[g][c] = at;
      at += 1u << (kPatternLayout.count[c] + 3);
    }
  }
  t[3][0] = at;  // the total
  return t;
}();

// Classes: 1 = voxel masks, 2 = brick cell masks, 3.. = internal nodes; version 5's pattern model is split by these 3 groups.
constexpr unsigned ClassGroup(int cls) { return cls <= 1 ? 0u : cls == 2 ? 1u : 2u; }

class MaskMixer5 {
 public:
  static constexpr int kApmContexts = 8 * 8 * 8 * 4;

  // `version`: the geometry stream's, 5 or 8 (8 starts the weights lower: below).
  explicit MaskMixer5(int version) : pattern_(kPatternBase[3][0]), side_(8 * 2 * 128), apm_(size_t{kApmContexts} * 33) {
    for (size_t cx = 0; cx < kApmContexts; ++cx) std::copy(kApmStart.begin(), kApmStart.end(), apm_.begin() + cx * 33);
    if (version >= 8) weights_.fill({19661, 13107, 13107, 13107, 13107, 0});
  }

  // Codes child c's bit. `context`: the version 2 model; `so_far`: the mask bits below c; `ones`: any of
  // them set; `faces`: which of the node's face neighbours exist (bits 0..2 the lower x, y, z, 3..5
  // the upper); `plane`: the plane memory state (0..26); `pattern`: the pattern model's index
  // (kPatternBase + the bits); `side`: which of the 7 neighbours on c's side exist; `apm`: the APM's
  // context. Trains the mixer on its own output (not the APM's), then every model.
  template <typename Io>
  int Bit(Io& io, YoungBitModel& context, int c, unsigned so_far, bool ones, unsigned faces, unsigned plane,
          unsigned pattern, unsigned side, unsigned apm, int truth) {
    const unsigned t = (1u << c) | so_far;
    YoungBitModel& sd = sides_[t << 6 | faces];
    YoungBitModel& pl = planes_[t * 27 + plane];
    CompactYoungModel& pt = pattern_[pattern];
    YoungBitModel& sm = side_[(c * 2 + (ones ? 1 : 0)) * 128 + side];
    std::array<int32_t, 6>& w = weights_[c * 2 + (ones ? 1 : 0)];
    const int32_t s0 = Stretch(context), s1 = Stretch(sd), s2 = Stretch(pl), s3 = Stretch(pt), s4 = Stretch(sm);
    const int64_t dot = int64_t{w[0]} * s0 + int64_t{w[1]} * s1 + int64_t{w[2]} * s2 + int64_t{w[3]} * s3 +
                        int64_t{w[4]} * s4 + int64_t{w[5]} * kBias;
    const int32_t d = static_cast<int32_t>(std::clamp<int64_t>(dot >> 16, -2047, 2047));
    const int32_t p1 = kSquashTable[static_cast<size_t>(d + 2047)];
    // The APM: buckets at d = −2048, −1920, .., 2048; the two around d, weighted by distance.
    const int32_t x = d + 2048, near = x & 127;
    uint16_t* a = &apm_[size_t{apm} * 33 + static_cast<size_t>(x >> 7)];
    const int32_t refined = (a[0] * (128 - near) + a[1] * near) >> 11;
    FixedP0 mixed{static_cast<uint32_t>(4096 - std::clamp((p1 + 3 * refined + 2) >> 2, 1, 4095))};
    const int bit = io.Bit(mixed, truth);
    const int32_t target = bit ? 65535 : 0;
    a[0] = static_cast<uint16_t>(a[0] + ((((target - a[0]) >> 6) * (128 - near)) >> 7));
    a[1] = static_cast<uint16_t>(a[1] + ((((target - a[1]) >> 6) * near) >> 7));
    const int32_t err = (bit << 12) - p1;
    w[0] = Train(w[0], s0, err);
    w[1] = Train(w[1], s1, err);
    w[2] = Train(w[2], s2, err);
    w[3] = Train(w[3], s3, err);
    w[4] = Train(w[4], s4, err);
    w[5] = Train(w[5], kBias, err);
    context.Update(bit);
    sd.Update(bit);
    pl.Update(bit);
    pt.Update(bit);
    sm.Update(bit);
    return bit;
  }

 private:
  static constexpr int32_t kBias = 256;
  // An APM row before training: the identity, P(1) at each bucket's d, in 1/65536.
  static constexpr auto kApmStart = [] {
    std::array<uint16_t, 33> t{};
    for (int j = 0; j < 33; ++j) t[j] = static_cast<uint16_t>(std::clamp(Squash((j - 16) * 128), 1, 4095) * 16);
    return t;
  }();
  static constexpr int32_t kMaxWeight = 1 << 22;
  template <typename M>
  static int32_t Stretch(const M& m) { return kStretchOfP0[m.P0() >> 1]; }
  // std::clamp's two selects per weight were a tenth of the mixer's instructions; the weights
  // rarely reach the limits, so one well-predicted branch decides.
  static int32_t Train(int32_t w, int32_t s, int32_t err) {
    const int32_t v = w + ((s * err) >> 11);
    if (__builtin_expect(static_cast<uint32_t>(v + kMaxWeight) > 2u * kMaxWeight, 0)) return v < 0 ? -kMaxWeight : kMaxWeight;
    return v;
  }

  std::array<YoungBitModel, 256 * 64> sides_{};
  std::array<YoungBitModel, 256 * 27> planes_{};
  std::vector<CompactYoungModel> pattern_;
  std::vector<YoungBitModel> side_;
  std::vector<uint16_t> apm_;
  // Version 5: the neighbour model starts trusted alone at 1, the others at 0.3 (the bias at 0).
  // Version 8: at 0.3 and 0.2: young models' first estimates are confident (3/4 after one bit), and
  // their sum at 2.2 overshot until the weights had learnt (tiny at 8 ft −31 bytes, −1.8 %; the
  // six other cases of bench --versus −0.01..−0.27 %; docs/benchmarks.md "Small scans' geometry").
  std::array<std::array<int32_t, 6>, 16> weights_ = [] {
    std::array<std::array<int32_t, 6>, 16> t{};
    t.fill({65536, 19661, 19661, 19661, 19661, 0});
    return t;
  }();
};

}  // namespace pointdag
