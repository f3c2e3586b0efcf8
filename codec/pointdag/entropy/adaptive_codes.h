// Small adaptive codes over the binary range coder, shared by the geometry and color streams.
//
// Bit tree: an n-bit symbol, most significant bit first, each bit with its own model chosen by the
// bits already coded (node 1, then node*2+bit), so the model learns the symbol's distribution.
// Gamma: a value v >= 1 as its bit length in unary (one model per position), then the top three
// bits below its leading one through a bit tree per length, then the rest equiprobable. It suits
// skewed values: back-reference ordinals, block lengths, endpoint differences.
#pragma once

#include <array>
#include <bit>
#include <cstdint>

#include "pointdag/entropy/binary_range_coder.h"

namespace pointdag {

template <int kBits>
struct BitTreeModel {
  std::array<BitModel, size_t{1} << kBits> node;
};

template <int kBits>
void EncodeBitTree(BinaryRangeEncoder& rc, BitTreeModel<kBits>& m, uint32_t value, int bits = kBits) {
  uint32_t node = 1;
  for (int i = bits - 1; i >= 0; --i) {
    const int bit = static_cast<int>((value >> i) & 1u);
    rc.Encode(m.node[node], bit);
    node = node << 1 | static_cast<uint32_t>(bit);
  }
}

// Both children's probabilities are read while the bit between them is decoded: the next decision
// then waits on a select, not on a load whose address that bit chooses.
template <int kBits>
uint32_t DecodeBitTree(BinaryRangeDecoder& rc, BitTreeModel<kBits>& m, int bits = kBits) {
  uint32_t node = 1, p0 = m.node[1].P0();
#pragma GCC unroll 8
  for (int i = 1; i < bits; ++i) {
    const uint32_t zero = m.node[2 * node].P0(), one = m.node[2 * node + 1].P0();
    const uint32_t bit = static_cast<uint32_t>(rc.Decode(m.node[node], p0));
    node = node << 1 | bit;
    p0 = bit ? one : zero;
  }
  if (bits > 0) node = node << 1 | static_cast<uint32_t>(rc.Decode(m.node[node], p0));
  return node - (1u << bits);
}

constexpr int kGammaModelledBits = 3;

struct GammaModel {
  std::array<BitModel, 33> length;
  std::array<BitTreeModel<kGammaModelledBits>, 33> top;
};

// `max_length`: bit width of the largest value possible, which spares the unary terminator there.
inline void EncodeGamma(BinaryRangeEncoder& rc, GammaModel& m, uint32_t v, int max_length = 32) {
  const int length = std::bit_width(v);
  for (int i = 1; i < length; ++i) rc.Encode(m.length[i], 1);
  if (length < max_length) rc.Encode(m.length[length], 0);
  const int modelled = std::min(length - 1, kGammaModelledBits);
  const int rest = length - 1 - modelled;
  EncodeBitTree<kGammaModelledBits>(rc, m.top[length], (v >> rest) & ((1u << modelled) - 1), modelled);
  rc.EncodeDirect(v & ((1u << rest) - 1), rest);
}

inline uint32_t DecodeGamma(BinaryRangeDecoder& rc, GammaModel& m, int max_length = 32) {
  int length = 1;
  while (length < max_length && rc.Decode(m.length[length])) ++length;
  const int modelled = std::min(length - 1, kGammaModelledBits);
  const int rest = length - 1 - modelled;
  uint32_t v = (1u << modelled) | DecodeBitTree<kGammaModelledBits>(rc, m.top[length], modelled);
  return v << rest | rc.DecodeDirect(rest);
}

// Signed values as gamma codes: 0, -1, 1, -2, ... -> 1, 2, 3, 4, ...
inline uint32_t ZigZag(int32_t v) { return (static_cast<uint32_t>(v) << 1 ^ static_cast<uint32_t>(v >> 31)) + 1; }
inline int32_t UnZigZag(uint32_t z) {
  const uint32_t u = z - 1;
  return static_cast<int32_t>(u >> 1) ^ -static_cast<int32_t>(u & 1);
}

}  // namespace pointdag
