// LASzip's GPSTIME11 item, version 2 (the 8-byte GPS time of LAS point formats 1, 3, 4, 5).
//
// The coder follows up to four interleaved time sequences (e.g. several scanners' pulses); each
// time is the raw 64-bit pattern of the double, predicted from its sequence's last time plus a
// multiple of the last difference. Contract as for Point10Decoder; in addition Decode() returns
// false when the stream switches sequences more often in one point than an encoder can write
// (hostile input: LASzip would recurse without bound there).
#pragma once

#include <cstdint>

#include "pointdag/read/laz/arithmetic_decoder.h"
#include "pointdag/read/laz/integer_decompressor.h"

namespace pointdag::laz {

class Gpstime11Decoder {
 public:
  static constexpr size_t kSize = 8;

  explicit Gpstime11Decoder(ArithmeticDecoder& decoder);
  void Init(const uint8_t* item);
  [[nodiscard]] bool Decode(uint8_t* out);

 private:
  void StartSequence();                 // a time too far from the last: its high half coded, its low half raw
  void AddDiff(int32_t diff, bool extreme);  // the new time of the current sequence

  ArithmeticDecoder& dec_;
  uint32_t last_ = 0, next_ = 0;  // the current sequence, the one a new sequence replaces
  uint64_t time_[4] = {};
  int32_t diff_[4] = {};
  int32_t extreme_count_[4] = {};  // differences far from the prediction in a row
  ArithmeticModel multi_model_;
  ArithmeticModel zero_diff_model_;
  IntegerDecompressor ic_;
};

}  // namespace pointdag::laz
