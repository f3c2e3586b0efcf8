// LASzip's BYTE item, version 2 (a point's extra bytes): each byte is coded as its difference
// from the same byte of the previous point, with one model per byte position.
//
// Contract as for Point10Decoder; the models are allocated once, for `count` bytes.
#pragma once

#include <cstdint>
#include <vector>

#include "pointdag/read/laz/arithmetic_decoder.h"

namespace pointdag::laz {

class ByteDecoder {
 public:
  // Extra bytes per point this decoder takes (about 2.4 KB of models each); LAS allows up to 65515,
  // real files carry a few dozen, so a larger item is refused rather than allocated.
  static constexpr size_t kMaxCount = 1024;

  ByteDecoder(ArithmeticDecoder& decoder, size_t count);
  void Init(const uint8_t* item);
  void Decode(uint8_t* out);

 private:
  ArithmeticDecoder& dec_;
  std::vector<uint8_t> last_;
  std::vector<ArithmeticModel> models_;
};

}  // namespace pointdag::laz
