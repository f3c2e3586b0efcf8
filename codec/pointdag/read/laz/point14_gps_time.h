// The GPS time of POINT14 (LASzip's read_gps_time of the layered items): the time's 64 bits as an
// integer, predicted from up to four interleaved time sequences (multiple pulses in the air), each
// with its last time and last difference. A point's time is coded as a multiple of its sequence's
// last difference plus a correction, as a 32-bit difference, as a switch to another sequence, or
// in full (a new sequence).
#pragma once

#include <array>
#include <cstdint>

#include "pointdag/read/laz/arithmetic_decoder.h"
#include "pointdag/read/laz/integer_decompressor.h"

namespace pointdag::laz {

class Point14GpsTime {
 public:
  // `decoder` is the gps_time layer's stream; it must outlive this object.
  explicit Point14GpsTime(ArithmeticDecoder& decoder);
  Point14GpsTime(const Point14GpsTime&) = delete;
  Point14GpsTime& operator=(const Point14GpsTime&) = delete;

  // Starts over (models and sequences) from the time of the point that opens the context.
  void Reset(uint64_t time);
  // Decodes the time of a point whose time changed. Returns false when the stream switches
  // sequences more often than an encoder can (a corrupt chunk); `time` is then unspecified.
  bool Decode(uint64_t& time);

 private:
  ArithmeticDecoder* decoder_;
  ArithmeticModel multi_;      // the multiplier (and the escapes) after a non-zero difference
  ArithmeticModel zero_diff_;  // the case after a zero difference
  IntegerDecompressor ic_;
  uint32_t last_ = 0, next_ = 0;  // the current sequence; where the next new one goes
  std::array<uint64_t, 4> times_{};
  std::array<int32_t, 4> diffs_{};
  std::array<int32_t, 4> extremes_{};  // how often in a row the multiplier was out of range
};

}  // namespace pointdag::laz
