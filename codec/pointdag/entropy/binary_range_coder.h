// Adaptive binary range coder: the carry-less scheme used by LZMA (Subbotin / Pavlov), with 12-bit
// probabilities that adapt by 1/32 per coded bit. Context models live in the caller: one
// BitModel per context. The decoder never reads past its input: missing bytes read as zero, so
// corrupt input decodes to garbage that the caller's structural checks reject, never to a crash.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace pointdag {

// Two estimates of P(bit = 0) in 1/65536, one adapting fast (1/16) and one slowly (1/128); their
// mean tracks both short runs and long-term statistics better than either alone.
struct BitModel {
  uint16_t fast = 32768, slow = 32768;
  uint32_t P0() const { return ((uint32_t{fast} + slow) >> 5) | 1u; }  // 12 bits, never 0
  void Update(int bit) {  // both moves computed and one selected: no branch on the bit
    const auto up = [](uint16_t p, int rate) { return static_cast<uint16_t>(p + ((65536 - p) >> rate)); };
    const auto down = [](uint16_t p, int rate) { return static_cast<uint16_t>(p - (p >> rate)); };
    fast = bit ? down(fast, 4) : up(fast, 4);
    slow = bit ? down(slow, 7) : up(slow, 7);
  }
};

// A BitModel that learns fast while young: both estimates move by 1/(n+2) after n updates until
// that is slower than their own rates. Suits many sparse contexts (the geometry's neighbour contexts).
struct YoungBitModel {
  uint16_t fast = 32768, slow = 32768;
  uint8_t n = 0;
  uint32_t P0() const { return ((uint32_t{fast} + slow) >> 5) | 1u; }
  void Update(int bit) {
    const int32_t target = bit ? 0 : 65535;
    const Rates r = kRates[n];
    fast = static_cast<uint16_t>(fast + (((target - fast) * r.fast) >> 16));
    slow = static_cast<uint16_t>(slow + (((target - slow) * r.slow) >> 16));
    if (n < kYoung) ++n;
  }

 private:
  struct Rates {
    int32_t fast, slow;  // in 1/65536
  };
  static constexpr int kYoung = 127;  // 1/(n+2) is below both rates from here on
  static constexpr std::array<Rates, kYoung + 1> kRates = [] {
    std::array<Rates, kYoung + 1> t{};
    for (int i = 0; i <= kYoung; ++i) t[i] = {std::max(65536 / (i + 2), 65536 >> 4), std::max(65536 / (i + 2), 65536 >> 7)};
    return t;
  }();
};

// One estimate where YoungBitModel keeps two: 4 bytes instead of 6, for large tables of sparse
// contexts that rarely outgrow the young phase (geometry version 5's pattern model: its bits equal
// to within 0.05 % of YoungBitModel's, the table two thirds the size). Moves by 1/(n+2) after n
// updates until that is below 1/128.
struct CompactYoungModel {
  uint16_t p = 32768;  // P(bit = 0) in 1/65536
  uint8_t n = 0;
  uint32_t P0() const { return (uint32_t{p} >> 4) | 1u; }
  void Update(int bit) {
    const int32_t target = bit ? 0 : 65535;
    p = static_cast<uint16_t>(p + (((target - p) * kRates[n]) >> 16));
    if (n < kYoung) ++n;
  }

 private:
  static constexpr int kYoung = 127;
  static constexpr std::array<int32_t, kYoung + 1> kRates = [] {
    std::array<int32_t, kYoung + 1> t{};
    for (int i = 0; i <= kYoung; ++i) t[i] = std::max(65536 / (i + 2), 65536 >> 7);
    return t;
  }();
};

// A YoungBitModel whose slow estimate keeps slowing down to 1/1024 (1/(n+2) after n updates): for
// statistics that hold over a whole scan, as the lossless colors' residuals do (lossless_mixing.cc:
// 0.1-0.8 % fewer bits than stopping at 1/128).
struct SteadyBitModel {
  uint16_t fast = 32768, slow = 32768;
  uint16_t n = 0;
  uint32_t P0() const { return ((uint32_t{fast} + slow) >> 5) | 1u; }
  void Update(int bit) {
    const int32_t target = bit ? 0 : 65535;
    fast = static_cast<uint16_t>(fast + (((target - fast) * kRate[std::min<int>(n, kFastest)]) >> 16));
    slow = static_cast<uint16_t>(slow + (((target - slow) * kRate[n]) >> 16));
    if (n < kSlowest) ++n;
  }

 private:
  static constexpr int kFastest = 14, kSlowest = 1023;  // rates 1/16 and 1/1025 from there on
  static constexpr std::array<int32_t, kSlowest + 1> kRate = [] {
    std::array<int32_t, kSlowest + 1> t{};
    for (int i = 0; i <= kSlowest; ++i) t[i] = 65536 / (i + 2);
    return t;
  }();
};

class BinaryRangeEncoder {
 public:
  // Branch-free, as the decoder: selects, not a branch on a coin-toss bit.
  template <typename Model>
  void Encode(Model& m, int bit) {
    const uint32_t bound = (range_ >> 12) * m.P0();
    const bool one = bit != 0;
    low_ += one ? bound : 0u;
    range_ = one ? range_ - bound : bound;
    m.Update(bit);
    Normalize();
  }
  // Equiprobable bits, for values with no useful model (back-reference ordinals).
  void EncodeDirect(uint32_t value, int bits) {
    for (int i = bits - 1; i >= 0; --i) {
      range_ >>= 1;
      if ((value >> i) & 1u) low_ += range_;
      Normalize();
    }
  }
  std::vector<uint8_t> Finish() {
    for (int i = 0; i < 5; ++i) ShiftLow();
    return std::move(out_);
  }
  // Finish() less what a decoder reading zeros past the end infers (geometry stream version 8): the
  // first byte (always 0: low starts below 2^32 and nothing carries into it) and the zero bytes
  // at the end, at most 4, after flushing the value in [low, low + range) with the most trailing
  // zero bits (range >= 2^24 here: its low 3 bytes at least are zero). Read it with `compact`.
  std::vector<uint8_t> FinishCompact() {
    for (int zeros = 32; zeros > 0; --zeros) {
      const uint64_t mask = (uint64_t{1} << zeros) - 1;
      const uint64_t rounded = (low_ + mask) & ~mask;
      if (rounded - low_ < range_) {
        low_ = rounded;
        break;
      }
    }
    for (int i = 0; i < 5; ++i) ShiftLow();
    for (int i = 0; i < 4 && out_.size() > 1 && out_.back() == 0; ++i) out_.pop_back();
    out_.erase(out_.begin());
    return std::move(out_);
  }

 private:
  // Most bits leave the range above 2^24: the test inline, the byte output out of line.
  void Normalize() {
    if (range_ < (1u << 24)) [[unlikely]] Renormalize();
  }
  [[gnu::noinline]] void Renormalize() {
    do {
      range_ <<= 8;
      ShiftLow();
    } while (range_ < (1u << 24));
  }
  void ShiftLow() {
    if (static_cast<uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
      const uint8_t carry = static_cast<uint8_t>(low_ >> 32);
      uint8_t pending = cache_;
      do {
        out_.push_back(static_cast<uint8_t>(pending + carry));
        pending = 0xFF;
      } while (--cache_size_ != 0);
      cache_ = static_cast<uint8_t>(low_ >> 24);
    }
    ++cache_size_;
    low_ = (low_ & 0x00FFFFFFu) << 8;
  }

  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;
  uint64_t cache_size_ = 1;
  std::vector<uint8_t> out_;
};

class BinaryRangeDecoder {
 public:
  // `compact`: the input was written by FinishCompact (its implied first byte is not read).
  explicit BinaryRangeDecoder(std::span<const uint8_t> in, bool compact = false) : in_(in) {
    for (int i = compact ? 1 : 0; i < 5; ++i) code_ = code_ << 8 | Next();
  }
  // Branch-free: the bit is a coin toss to the branch predictor, selects are not.
  template <typename Model>
  int Decode(Model& m) {
    return Decode(m, m.P0());
  }
  // With `p0` = m.P0() read beforehand (DecodeBitTree reads both children's before their parent's bit).
  template <typename Model>
  int Decode(Model& m, uint32_t p0) {
    const uint32_t bound = (range_ >> 12) * p0;
    const bool one = code_ >= bound;
    code_ -= one ? bound : 0u;
    range_ = one ? range_ - bound : bound;
    const int bit = one ? 1 : 0;
    m.Update(bit);
    Normalize();
    return bit;
  }
  uint32_t DecodeDirect(int bits) {
    uint32_t value = 0;
    for (int i = 0; i < bits; ++i) {
      range_ >>= 1;
      const uint32_t bit = code_ >= range_ ? 1u : 0u;
      if (bit) code_ -= range_;
      value = value << 1 | bit;
      Normalize();
    }
    return value;
  }
  // True once the decoder has wanted more bytes than the input had: the stream was truncated (a
  // compact one reads at most its 4 dropped zero bytes past its end).
  bool overrun() const { return read_ > in_.size() + 4; }
  // True when the decoder has read exactly its input, as it does on what Finish() wrote: a stream
  // that must fill its bytes can then refuse both truncation and trailing bytes.
  bool consumed_exactly() const { return read_ == in_.size(); }

 private:
  // Bytes past the input read as zero; `read_` counts them too (overrun).
  uint8_t Next() {
    const uint8_t byte = read_ < in_.size() ? in_[read_] : 0;
    ++read_;
    return byte;
  }
  // Inline, unlike the encoder's: an out-of-line call made tile decode 5-10 % slower (bench --versus).
  void Normalize() {
    while (range_ < (1u << 24)) {
      range_ <<= 8;
      code_ = code_ << 8 | Next();
    }
  }

  std::span<const uint8_t> in_;
  size_t read_ = 0;  // bytes consumed, those past the input included
  uint32_t code_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
};

}  // namespace pointdag
