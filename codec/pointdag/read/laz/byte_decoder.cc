#include "pointdag/read/laz/byte_decoder.h"

#include <cstring>

namespace pointdag::laz {

ByteDecoder::ByteDecoder(ArithmeticDecoder& decoder, size_t count) : dec_(decoder), last_(count) {
  models_.reserve(count);
  for (size_t i = 0; i < count; ++i) models_.emplace_back(256);
}

void ByteDecoder::Init(const uint8_t* item) {
  std::memcpy(last_.data(), item, last_.size());
  for (ArithmeticModel& m : models_) m.Reset();
}

void ByteDecoder::Decode(uint8_t* out) {
  for (size_t i = 0; i < last_.size(); ++i) {
    last_[i] = static_cast<uint8_t>(last_[i] + dec_.DecodeSymbol(models_[i]));
  }
  std::memcpy(out, last_.data(), last_.size());
}

}  // namespace pointdag::laz
