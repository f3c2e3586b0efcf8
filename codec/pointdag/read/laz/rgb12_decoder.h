// LASzip's RGB12 item, version 2 (the three 16-bit colour channels of point formats 2, 3, 5).
//
// Each byte of each channel is coded apart; green and blue are predicted from red's change, and
// a flag says when all three channels are equal (grey). Contract as for Point10Decoder.
#pragma once

#include <cstdint>

#include "pointdag/read/laz/arithmetic_decoder.h"

namespace pointdag::laz {

class Rgb12Decoder {
 public:
  static constexpr size_t kSize = 6;

  explicit Rgb12Decoder(ArithmeticDecoder& decoder);
  void Init(const uint8_t* item);
  void Decode(uint8_t* out);

 private:
  ArithmeticDecoder& dec_;
  uint16_t last_[3] = {};  // red, green, blue of the previous point
  ArithmeticModel changed_;  // which of the six bytes changed, and whether the point is grey
  // One model per byte: 0 red low, 1 red high, 2 green low, 3 green high, 4 blue low, 5 blue high.
  ArithmeticModel diff_[6] = {ArithmeticModel(256), ArithmeticModel(256), ArithmeticModel(256),
                              ArithmeticModel(256), ArithmeticModel(256), ArithmeticModel(256)};
};

}  // namespace pointdag::laz
