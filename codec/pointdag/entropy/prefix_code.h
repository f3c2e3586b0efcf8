// Canonical prefix (Huffman) codes over bytes, for streams decoded by table lookup: one lookup of
// kPrefixCodeBits bits per symbol instead of a chain of adaptive binary decisions (geometry coder 3,
// proto/PDAG_FORMAT.md §2.2). Bits are read most significant first; past the end they read as 0.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/status.h"

namespace pointdag {

constexpr int kPrefixCodeBits = 12;  // the longest code, and the lookup's width

// Code lengths (0 = symbol absent, else 1..kPrefixCodeBits) of a Huffman code for `freq`, made
// length-limited by halving the frequencies until it fits. A single symbol gets length 1.
std::array<uint8_t, 256> PrefixCodeLengths(const std::array<uint64_t, 256>& freq);

class BitWriter {
 public:
  void Put(uint32_t code, int length);
  std::vector<uint8_t> Finish();  // zero-padded to a byte

 private:
  std::vector<uint8_t> bytes_;
  uint64_t acc_ = 0;
  int bits_ = 0;
};

class PrefixEncoder {
 public:
  explicit PrefixEncoder(const std::array<uint8_t, 256>& lengths);
  void Put(BitWriter& out, uint8_t symbol) const { out.Put(code_[symbol], lengths_[symbol]); }

 private:
  std::array<uint8_t, 256> lengths_;
  std::array<uint16_t, 256> code_{};
};

// The canonical code of some lengths as a lookup table of `bits`-bit patterns, `bits` the longest
// code (the table has 2^bits entries): a small tile's codes of a few bits fill a few hundred entries,
// not 4096 (building full tables was a fifth of the decode of a 1,000-voxel scan's tiles).
// Entry: symbol | length << 8; length 0 marks a bit pattern no code starts with.
struct PrefixTable {
  int bits = 0;
  std::vector<uint16_t> entries = std::vector<uint16_t>(1, 0);
};

// The canonical code of `lengths` (codes in order of length, then symbol) as a lookup table;
// kCorrupt when the lengths over-subscribe the code space (Kraft sum above 1).
Status BuildPrefixTable(const std::array<uint8_t, 256>& lengths, PrefixTable& table);

class PrefixDecoder {
 public:
  explicit PrefixDecoder(std::span<const uint8_t> bytes) : bytes_(bytes) {}
  // The next symbol, or -1 at a bit pattern that is no code.
  int Get(const PrefixTable& table) {
    const uint16_t e = table.entries[Peek() >> (kPrefixCodeBits - table.bits)];
    pos_ += e >> 8;
    return (e >> 8) ? (e & 0xFF) : -1;
  }
  // `n` (0..31) raw bits, most significant first.
  uint32_t Bits(int n) {
    uint32_t v = 0;
    for (; n > 0;) {
      const int take = n < kPrefixCodeBits ? n : kPrefixCodeBits;
      v = v << take | Peek() >> (kPrefixCodeBits - take);
      pos_ += static_cast<uint64_t>(take);
      n -= take;
    }
    return v;
  }
  bool overrun() const { return pos_ > 8 * bytes_.size(); }

 private:
  uint32_t Peek() const {
    const size_t at = pos_ >> 3;
    uint32_t v;
    if (at + 3 <= bytes_.size()) {
      v = uint32_t{bytes_[at]} << 16 | uint32_t{bytes_[at + 1]} << 8 | bytes_[at + 2];
    } else {
      v = 0;
      for (size_t k = 0; k < 3; ++k) v = v << 8 | (at + k < bytes_.size() ? bytes_[at + k] : 0u);
    }
    return (v >> (12 - (pos_ & 7))) & ((1u << kPrefixCodeBits) - 1);
  }
  std::span<const uint8_t> bytes_;
  uint64_t pos_ = 0;
};

}  // namespace pointdag
