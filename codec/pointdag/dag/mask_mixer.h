// Geometry stream version 3 (proto/PDAG_FORMAT.md §2.2): each mask bit's probability is a logistic
// mix of three models' predictions, as context-mixing compressors combine them, instead of the one
// neighbour-context model of version 2. The neighbour model alone dilutes when given more context
// (measured: finer side states; the octant and neighbour counts before); mixing adds the mask so far and
// the parent's mask beside it, each in its own model, and learns per child how far to trust each.
// All integer (12-bit probabilities, stretch in 1/256 nats, weights in 1/65536) so that every
// decoder, the JavaScript one included, computes the same bits.
// Version 4 mixes two more models: the mask so far split by which of the node's six face neighbours
// exist (the surface's orientation around it), and split by the plane memory (spatial_coder.cc:
// whether the last coded cell on each of the child's three planes had children there, G-PCC's
// planar idea), which reaches beyond the neighbours: −1.1..−6.3 % on every scan but tiny (+0.1 %).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "pointdag/entropy/binary_range_coder.h"
#include "pointdag/entropy/logistic.h"

namespace pointdag {

// kStretch[4096 - p0] by p0 >> 1: a model's P0 is odd, so half the entries (4 kB beside the
// mixers' other tables in the L1 cache) and no subtraction per input.
constexpr auto kStretchOfP0 = [] {
  std::array<int16_t, 2048> t{};
  for (uint32_t h = 0; h < 2048; ++h) t[h] = kStretch[4096 - (2 * h + 1)];
  return t;
}();

// The mixer's own models and weights for one stream, shared by all classes (per class measured
// no better: −0.1..+1.4 %); 100 kB (version 4: 240 kB), small enough to start afresh for every tile.
class MaskMixer {
 public:
  // `more`: version 4's models (sides_, planes_ below); without them their inputs stay 0 (version 3).
  explicit MaskMixer(bool more) : more_(more) {}

  // Mixes `context` (the version 2 model) with the models of the mask so far, of (child, parent's
  // mask, lower neighbours) and (version 4) of (mask so far, `faces`: which of the node's face
  // neighbours exist, bits 0..2 the lower x, y, z, 3..5 the upper) and of (mask so far, `plane`:
  // the child's plane memory state, 0..26); codes the bit with the mix, then trains all of them.
  template <typename Io>
  int Bit(Io& io, YoungBitModel& context, int c, unsigned so_far, unsigned parent, unsigned lower, bool ones,
          unsigned faces, unsigned plane, int truth) {
    YoungBitModel& tree = tree_[(1u << c) | so_far];
    YoungBitModel& par = parent_[(parent * 8 + c) * 8 + lower];  // a node's rows together: fewer cache lines
    YoungBitModel& side = sides_[(((1u << c) | so_far) << 6) | faces];
    YoungBitModel& pln = planes_[((1u << c) | so_far) * 27 + plane];
    std::array<int32_t, 6>& w = weights_[c * 2 + (ones ? 1 : 0)];
    // Spelled out rather than looped: the loops stayed loops, through the stack, on the per-bit path.
    const int32_t s0 = Stretch(context), s1 = Stretch(tree), s2 = Stretch(par);
    const int32_t s3 = more_ ? Stretch(side) : 0, s4 = more_ ? Stretch(pln) : 0;
    const int64_t dot = int64_t{w[0]} * s0 + int64_t{w[1]} * s1 + int64_t{w[2]} * s2 + int64_t{w[3]} * kBias +
                        int64_t{w[4]} * s3 + int64_t{w[5]} * s4;
    const int32_t p1 = kSquashTable[static_cast<size_t>(std::clamp<int64_t>(dot >> 16, -2047, 2047) + 2047)];
    FixedP0 mixed{static_cast<uint32_t>(4096 - p1)};
    const int bit = io.Bit(mixed, truth);
    const int32_t err = (bit << 12) - p1;
    w[0] = Train(w[0], s0, err);
    w[1] = Train(w[1], s1, err);
    w[2] = Train(w[2], s2, err);
    w[3] = Train(w[3], kBias, err);
    w[4] = Train(w[4], s3, err);
    w[5] = Train(w[5], s4, err);
    context.Update(bit);
    tree.Update(bit);
    par.Update(bit);
    if (more_) {
      side.Update(bit);
      pln.Update(bit);
    }
    return bit;
  }

 private:
  static constexpr int32_t kBias = 256;
  static constexpr int32_t kMaxWeight = 1 << 22;
  // The neighbour model starts trusted alone at 1, the others at 0.3 (the bias at 0).
  static constexpr std::array<int32_t, 6> kInitialWeights = {65536, 19661, 19661, 0, 19661, 19661};
  static int32_t Stretch(const YoungBitModel& m) { return kStretchOfP0[m.P0() >> 1]; }
  static int32_t Train(int32_t w, int32_t s, int32_t err) { return std::clamp(w + ((s * err) >> 11), -kMaxWeight, kMaxWeight); }

  std::array<YoungBitModel, 256> tree_{};
  std::array<YoungBitModel, 8 * 256 * 8> parent_{};
  std::array<YoungBitModel, 256 * 64> sides_{};
  std::array<YoungBitModel, 256 * 27> planes_{};
  bool more_;
  std::array<std::array<int32_t, 6>, 16> weights_ = [] {
    std::array<std::array<int32_t, 6>, 16> t{};
    t.fill(kInitialWeights);
    return t;
  }();
};

}  // namespace pointdag
