#include "pointdag/read/laz/arithmetic_decoder.h"

namespace pointdag::laz {
namespace {

constexpr uint32_t kMinLength = 0x01000000U;
constexpr uint32_t kMaxLength = 0xFFFFFFFFU;
constexpr uint32_t kBitLengthShift = 13;  // bit models: probabilities in 13 bits
constexpr uint32_t kBitMaxCount = 1U << kBitLengthShift;
constexpr uint32_t kLengthShift = 15;  // multi-symbol models: 15-bit distributions
constexpr uint32_t kMaxCount = 1U << kLengthShift;

}  // namespace

void ArithmeticBitModel::Reset() {
  bit_0_count_ = 1;
  bit_count_ = 2;
  bit_0_prob_ = 1U << (kBitLengthShift - 1);
  update_cycle_ = bits_until_update_ = 4;
}

void ArithmeticBitModel::Update() {
  if ((bit_count_ += update_cycle_) > kBitMaxCount) {
    bit_count_ = (bit_count_ + 1) >> 1;
    bit_0_count_ = (bit_0_count_ + 1) >> 1;
    if (bit_0_count_ == bit_count_) ++bit_count_;
  }
  const uint32_t scale = 0x80000000U / bit_count_;
  bit_0_prob_ = (bit_0_count_ * scale) >> (31 - kBitLengthShift);
  update_cycle_ = (5 * update_cycle_) >> 2;
  if (update_cycle_ > 64) update_cycle_ = 64;
  bits_until_update_ = update_cycle_;
}

ArithmeticModel::ArithmeticModel(uint32_t symbols) : symbols_(symbols), last_symbol_(symbols - 1) {
  // Callers only build models of 2..2048 symbols (LASzip's limits); the table speeds up large ones.
  if (symbols_ > 16) {
    uint32_t table_bits = 3;
    while (symbols_ > (1U << (table_bits + 2))) ++table_bits;
    table_size_ = 1U << table_bits;
    table_shift_ = kLengthShift - table_bits;
    decoder_table_.resize(table_size_ + 2);
  }
  distribution_.resize(symbols_);
  symbol_count_.resize(symbols_);
  Reset();
}

void ArithmeticModel::Reset() {
  total_count_ = 0;
  update_cycle_ = symbols_;
  for (auto& c : symbol_count_) c = 1;
  Update();
  symbols_until_update_ = update_cycle_ = (symbols_ + 6) >> 1;
}

void ArithmeticModel::Update() {
  if ((total_count_ += update_cycle_) > kMaxCount) {
    total_count_ = 0;
    for (auto& c : symbol_count_) total_count_ += (c = (c + 1) >> 1);
  }
  uint32_t sum = 0, s = 0;
  const uint32_t scale = 0x80000000U / total_count_;
  if (table_size_ == 0) {
    for (uint32_t k = 0; k < symbols_; ++k) {
      distribution_[k] = (scale * sum) >> (31 - kLengthShift);
      sum += symbol_count_[k];
    }
  } else {
    for (uint32_t k = 0; k < symbols_; ++k) {
      distribution_[k] = (scale * sum) >> (31 - kLengthShift);
      sum += symbol_count_[k];
      const uint32_t w = distribution_[k] >> table_shift_;
      while (s < w) decoder_table_[++s] = k - 1;
    }
    decoder_table_[0] = 0;
    while (s <= table_size_) decoder_table_[++s] = symbols_ - 1;
  }
  update_cycle_ = (5 * update_cycle_) >> 2;
  const uint32_t max_cycle = (symbols_ + 6) << 3;
  if (update_cycle_ > max_cycle) update_cycle_ = max_cycle;
  symbols_until_update_ = update_cycle_;
}

void ArithmeticDecoder::Init(const uint8_t* begin, const uint8_t* end) {
  begin_ = next_ = begin;
  end_ = end;
  overran_ = false;
  length_ = kMaxLength;
  value_ = uint32_t{NextByte()} << 24;
  value_ |= uint32_t{NextByte()} << 16;
  value_ |= uint32_t{NextByte()} << 8;
  value_ |= uint32_t{NextByte()};
}

void ArithmeticDecoder::Renormalize() {
  do {
    value_ = (value_ << 8) | NextByte();
  } while ((length_ <<= 8) < kMinLength);
}

uint32_t ArithmeticDecoder::DecodeBit(ArithmeticBitModel& m) {
  const uint32_t x = m.bit_0_prob_ * (length_ >> kBitLengthShift);
  const uint32_t bit = value_ >= x ? 1 : 0;
  if (bit == 0) {
    length_ = x;
    ++m.bit_0_count_;
  } else {
    value_ -= x;
    length_ -= x;
  }
  if (length_ < kMinLength) Renormalize();
  if (--m.bits_until_update_ == 0) m.Update();
  return bit;
}

uint32_t ArithmeticDecoder::DecodeSymbol(ArithmeticModel& m) {
  uint32_t n, sym, x, y = length_;
  if (m.table_size_ != 0) {
    length_ >>= kLengthShift;
    // A corrupt stream can make value >= length; LASzip would index past its table there.
    const uint32_t dv = length_ == 0 ? 0 : value_ / length_;
    const uint32_t t = dv >> m.table_shift_;
    if (t >= m.table_size_) {
      sym = m.last_symbol_;
      n = m.symbols_;
    } else {
      sym = m.decoder_table_[t];
      n = m.decoder_table_[t + 1] + 1;
    }
    while (n > sym + 1) {  // binary search in the table's range
      const uint32_t k = (sym + n) >> 1;
      if (m.distribution_[k] > dv) {
        n = k;
      } else {
        sym = k;
      }
    }
    x = m.distribution_[sym] * length_;
    if (sym != m.last_symbol_) y = m.distribution_[sym + 1] * length_;
  } else {
    x = sym = 0;
    length_ >>= kLengthShift;
    uint32_t k = (n = m.symbols_) >> 1;
    do {  // bisection over the distribution
      const uint32_t z = length_ * m.distribution_[k];
      if (z > value_) {
        n = k;
        y = z;
      } else {
        sym = k;
        x = z;
      }
    } while ((k = (sym + n) >> 1) != sym);
  }
  value_ -= x;
  length_ = y - x;
  if (length_ < kMinLength) Renormalize();
  ++m.symbol_count_[sym];
  if (--m.symbols_until_update_ == 0) m.Update();
  return sym;
}

uint32_t ArithmeticDecoder::ReadBits(uint32_t bits) {
  if (bits > 19) {
    const uint32_t low = ReadShort();
    const uint32_t high = ReadBits(bits - 16) << 16;
    return high | low;
  }
  const uint32_t sym = value_ / (length_ >>= bits);
  value_ -= length_ * sym;
  if (length_ < kMinLength) Renormalize();
  return sym;
}

uint32_t ArithmeticDecoder::ReadByte() { return ReadBits(8) & 0xFF; }
uint32_t ArithmeticDecoder::ReadShort() { return ReadBits(16) & 0xFFFF; }

uint32_t ArithmeticDecoder::ReadInt() {
  const uint32_t low = ReadShort();
  const uint32_t high = ReadShort();
  return (high << 16) | low;
}

uint64_t ArithmeticDecoder::ReadInt64() {
  const uint64_t low = ReadInt();
  const uint64_t high = ReadInt();
  return (high << 32) | low;
}

}  // namespace pointdag::laz
