#include "pointdag/read/laz/integer_decompressor.h"

#include <algorithm>
#include <limits>

namespace pointdag::laz {

IntegerDecompressor::IntegerDecompressor(ArithmeticDecoder& decoder, uint32_t bits, uint32_t contexts,
                                         uint32_t bits_high, uint32_t range)
    : decoder_(&decoder), contexts_(contexts), bits_high_(bits_high) {
  if (range != 0) {  // the number of bits needed to code corrections within the range
    corr_range_ = range;
    while (range != 0) {
      range >>= 1;
      ++corr_bits_;
    }
    if (corr_range_ == (1U << (corr_bits_ - 1))) --corr_bits_;
    corr_min_ = -static_cast<int32_t>(corr_range_ / 2);
  } else if (bits != 0 && bits < 32) {
    corr_bits_ = bits;
    corr_range_ = 1U << bits;
    corr_min_ = -static_cast<int32_t>(corr_range_ / 2);
  } else {
    corr_bits_ = 32;
    corr_range_ = 0;
    corr_min_ = std::numeric_limits<int32_t>::min();
  }
  bits_models_.reserve(contexts_);
  for (uint32_t i = 0; i < contexts_; ++i) bits_models_.emplace_back(corr_bits_ + 1);
  correctors_.reserve(corr_bits_);
  for (uint32_t i = 1; i <= corr_bits_; ++i) correctors_.emplace_back(1U << std::min(i, bits_high_));
}

void IntegerDecompressor::Reset() {
  for (auto& m : bits_models_) m.Reset();
  corrector0_.Reset();
  for (auto& m : correctors_) m.Reset();
}

int32_t IntegerDecompressor::Decompress(int32_t prediction, uint32_t context) {
  // Unsigned arithmetic: the sum wraps exactly like LASzip's 32-bit ints, without signed overflow.
  uint32_t real = static_cast<uint32_t>(prediction) + static_cast<uint32_t>(ReadCorrector(bits_models_[context]));
  if (static_cast<int32_t>(real) < 0) {
    real += corr_range_;
  } else if (corr_range_ != 0 && real >= corr_range_) {
    real -= corr_range_;
  }
  return static_cast<int32_t>(real);
}

int32_t IntegerDecompressor::ReadCorrector(ArithmeticModel& bits_model) {
  k_ = decoder_->DecodeSymbol(bits_model);
  if (k_ == 0) return static_cast<int32_t>(decoder_->DecodeBit(corrector0_));
  if (k_ >= 32) return corr_min_;
  uint32_t c;
  if (k_ <= bits_high_) {
    c = decoder_->DecodeSymbol(correctors_[k_ - 1]);
  } else {  // the high bits through the model, the low k - bits_high bits raw
    const uint32_t k1 = k_ - bits_high_;
    c = decoder_->DecodeSymbol(correctors_[k_ - 1]);
    c = (c << k1) | decoder_->ReadBits(k1);
  }
  // Map [0, 2^k) back to the corrections of length k: [-(2^k - 1), -2^(k-1)] and [2^(k-1), 2^k].
  if (c >= (1U << (k_ - 1))) return static_cast<int32_t>(c + 1);
  return static_cast<int32_t>(c - ((1U << k_) - 1));
}

}  // namespace pointdag::laz
