// LASzip's GPS time coder, shared by the GPSTIME11 item (v2, point formats 1 and 3) and the
// gps_time layer of POINT14 (v3/v4, point formats 6-10).
//
// A time is the raw 64-bit pattern of the double, predicted from up to four interleaved time
// sequences (several pulses in the air), each with its last time and last difference. A point's
// time is coded as a multiple of its sequence's last difference plus a correction, as a 32-bit
// difference, as a switch to another sequence, or in full (a new sequence). The two items number
// their codes differently: GPSTIME11 also has an "unchanged" code, which POINT14 signals in its
// own flags instead; everything else is the same algorithm.
#pragma once

#include <array>
#include <cstdint>

#include "pointdag/read/laz/arithmetic_decoder.h"
#include "pointdag/read/laz/integer_decompressor.h"

namespace pointdag::laz {

enum class GpsTimeCodes { kGpsTime11, kPoint14 };

class GpsTimeDecoder {
 public:
  // `decoder` is the stream the times come from; it must outlive this object.
  GpsTimeDecoder(ArithmeticDecoder& decoder, GpsTimeCodes codes);
  GpsTimeDecoder(const GpsTimeDecoder&) = delete;
  GpsTimeDecoder& operator=(const GpsTimeDecoder&) = delete;

  // Starts over (models and sequences) from the time of the chunk's (or context's) first point.
  void Reset(uint64_t time);
  // Decodes the next time. Returns false when the stream switches sequences more often in one
  // point than an encoder can write (LASzip would recurse without bound there); `time` is then
  // unspecified.
  [[nodiscard]] bool Decode(uint64_t& time);

 private:
  void StartSequence();
  void CountExtreme(int32_t diff);

  ArithmeticDecoder* decoder_;
  GpsTimeCodes codes_;
  ArithmeticModel multi_;      // the multiplier (and the escapes) after a non-zero difference
  ArithmeticModel zero_diff_;  // the case after a zero difference
  IntegerDecompressor ic_;
  uint32_t last_ = 0, next_ = 0;  // the current sequence; where the next new one goes
  std::array<uint64_t, 4> times_{};
  std::array<int32_t, 4> diffs_{};
  std::array<int32_t, 4> extremes_{};  // how often in a row the difference was out of range
};

}  // namespace pointdag::laz
