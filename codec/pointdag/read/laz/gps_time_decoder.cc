#include "pointdag/read/laz/gps_time_decoder.h"

namespace pointdag::laz {
namespace {

// GPSTIME11's codes after a non-zero difference: 0..500 multiply the last difference (0: a new
// difference), 501..510 are the multipliers -1..-10, 511 "unchanged", 512 a full time (a new
// sequence), 513..515 a switch to sequence last+1..3. POINT14 has no 511: its codes from 511 on are
// one less. After a zero difference: 0 unchanged, 1 a 32-bit difference, 2 a new sequence, 3..5 a
// switch; POINT14 again lacks "unchanged".
constexpr int32_t kMulti = 500;
constexpr int32_t kMultiMinus = -10;
constexpr uint32_t kUnchanged = kMulti - kMultiMinus + 1;
constexpr uint32_t kFull = kMulti - kMultiMinus + 2;
constexpr uint32_t kMultiSymbols = kMulti - kMultiMinus + 6;
constexpr uint32_t kZeroDiffSymbols = 6;
// An encoder switches sequence at most once per point; a few rounds more bound corrupt input.
constexpr int kMaxRounds = 4;

// Multiplier times difference with the wrap-around of LASzip's 32-bit ints, without signed overflow.
int32_t Times(int32_t multi, int32_t diff) {
  return static_cast<int32_t>(static_cast<uint32_t>(multi) * static_cast<uint32_t>(diff));
}

uint64_t Plus(uint64_t time, int32_t diff) { return time + static_cast<uint64_t>(static_cast<int64_t>(diff)); }

}  // namespace

GpsTimeDecoder::GpsTimeDecoder(ArithmeticDecoder& decoder, GpsTimeCodes codes)
    : decoder_(&decoder),
      codes_(codes),
      multi_(codes == GpsTimeCodes::kPoint14 ? kMultiSymbols - 1 : kMultiSymbols),
      zero_diff_(codes == GpsTimeCodes::kPoint14 ? kZeroDiffSymbols - 1 : kZeroDiffSymbols),
      ic_(decoder, 32, 9) {}

void GpsTimeDecoder::Reset(uint64_t time) {
  multi_.Reset();
  zero_diff_.Reset();
  ic_.Reset();
  last_ = next_ = 0;
  times_ = {time, 0, 0, 0};
  diffs_ = {};
  extremes_ = {};
}

// A new sequence: the high half as a correction of the current one's, the low half raw.
void GpsTimeDecoder::StartSequence() {
  next_ = (next_ + 1) & 3;
  const auto high = static_cast<uint32_t>(ic_.Decompress(static_cast<int32_t>(times_[last_] >> 32), 8));
  times_[next_] = (uint64_t{high} << 32) | decoder_->ReadInt();
  last_ = next_;
  diffs_[last_] = 0;
  extremes_[last_] = 0;
}

// A difference that stayed out of the multipliers' range four times becomes the new last one.
void GpsTimeDecoder::CountExtreme(int32_t diff) {
  if (++extremes_[last_] > 3) {
    diffs_[last_] = diff;
    extremes_[last_] = 0;
  }
}

bool GpsTimeDecoder::Decode(uint64_t& time) {
  const bool point14 = codes_ == GpsTimeCodes::kPoint14;
  for (int round = 0; round < kMaxRounds; ++round) {
    if (diffs_[last_] == 0) {
      const uint32_t code = decoder_->DecodeSymbol(zero_diff_) + (point14 ? 1 : 0);
      if (code == 1) {  // a 32-bit difference
        diffs_[last_] = ic_.Decompress(0, 0);
        times_[last_] = Plus(times_[last_], diffs_[last_]);
        extremes_[last_] = 0;
      } else if (code == 2) {
        StartSequence();
      } else if (code > 2) {  // another sequence, then its own code
        last_ = (last_ + code - 2) & 3;
        continue;
      }
    } else {
      uint32_t code = decoder_->DecodeSymbol(multi_);
      if (point14 && code >= kUnchanged) ++code;
      const int32_t last_diff = diffs_[last_];
      if (code == 1) {  // the regular case: the same difference again
        times_[last_] = Plus(times_[last_], ic_.Decompress(last_diff, 1));
        extremes_[last_] = 0;
      } else if (code < kUnchanged) {
        int32_t diff;
        if (code == 0) {
          diff = ic_.Decompress(0, 7);
          CountExtreme(diff);
        } else if (code < static_cast<uint32_t>(kMulti)) {
          const auto multi = static_cast<int32_t>(code);
          diff = ic_.Decompress(Times(multi, last_diff), multi < 10 ? 2 : 3);
        } else if (code == static_cast<uint32_t>(kMulti)) {
          diff = ic_.Decompress(Times(kMulti, last_diff), 4);
          CountExtreme(diff);
        } else {
          const int32_t multi = kMulti - static_cast<int32_t>(code);  // -1..-10
          if (multi > kMultiMinus) {
            diff = ic_.Decompress(Times(multi, last_diff), 5);
          } else {
            diff = ic_.Decompress(Times(kMultiMinus, last_diff), 6);
            CountExtreme(diff);
          }
        }
        times_[last_] = Plus(times_[last_], diff);
      } else if (code == kFull) {
        StartSequence();
      } else if (code > kFull) {  // another sequence, then its own code
        last_ = (last_ + code - kFull) & 3;
        continue;
      }
    }
    time = times_[last_];  // kUnchanged (GPSTIME11 only) falls through: the same time again
    return true;
  }
  return false;
}

}  // namespace pointdag::laz
