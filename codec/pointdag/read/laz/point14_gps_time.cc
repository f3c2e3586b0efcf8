#include "pointdag/read/laz/point14_gps_time.h"

namespace pointdag::laz {
namespace {

// LASzip's multiplier codes: 1..499 multiply the last difference, 500 and beyond are clamped,
// 501..510 are the negative multipliers -1..-10, 511 a full time, 512..514 a switch of sequence.
constexpr int32_t kMulti = 500;
constexpr int32_t kMultiMinus = -10;
constexpr uint32_t kCodeFull = kMulti - kMultiMinus + 1;
constexpr uint32_t kMultiSymbols = kMulti - kMultiMinus + 5;
// An encoder switches at most once per point (to a sequence the time then fits); a few rounds more
// than that bound the loop on corrupt input.
constexpr int kMaxRounds = 4;

// Multiplier times difference with the wrap-around of LASzip's 32-bit ints, without signed overflow.
int32_t Times(int32_t multi, int32_t diff) {
  return static_cast<int32_t>(static_cast<uint32_t>(multi) * static_cast<uint32_t>(diff));
}

uint64_t Plus(uint64_t time, int32_t diff) { return time + static_cast<uint64_t>(static_cast<int64_t>(diff)); }

}  // namespace

Point14GpsTime::Point14GpsTime(ArithmeticDecoder& decoder)
    : decoder_(&decoder), multi_(kMultiSymbols), zero_diff_(5), ic_(decoder, 32, 9) {}

void Point14GpsTime::Reset(uint64_t time) {
  multi_.Reset();
  zero_diff_.Reset();
  ic_.Reset();
  last_ = next_ = 0;
  times_ = {time, 0, 0, 0};
  diffs_ = {};
  extremes_ = {};
}

bool Point14GpsTime::Decode(uint64_t& time) {
  // A difference that stayed out of the multipliers' range four times becomes the new last one.
  const auto count_extreme = [this](int32_t diff) {
    if (++extremes_[last_] > 3) {
      diffs_[last_] = diff;
      extremes_[last_] = 0;
    }
  };
  // A new sequence: the high half as a correction of the current one's, the low half raw.
  const auto start_sequence = [this] {
    next_ = (next_ + 1) & 3;
    const auto high = static_cast<uint32_t>(ic_.Decompress(static_cast<int32_t>(times_[last_] >> 32), 8));
    times_[next_] = (uint64_t{high} << 32) | decoder_->ReadInt();
    last_ = next_;
    diffs_[last_] = 0;
    extremes_[last_] = 0;
  };
  for (int round = 0; round < kMaxRounds; ++round) {
    if (diffs_[last_] == 0) {
      const uint32_t code = decoder_->DecodeSymbol(zero_diff_);
      if (code == 0) {  // a 32-bit difference
        diffs_[last_] = ic_.Decompress(0, 0);
        times_[last_] = Plus(times_[last_], diffs_[last_]);
        extremes_[last_] = 0;
      } else if (code == 1) {
        start_sequence();
      } else {  // 2..4: another sequence, then its own code
        last_ = (last_ + code - 1) & 3;
        continue;
      }
    } else {
      const uint32_t code = decoder_->DecodeSymbol(multi_);
      const int32_t last_diff = diffs_[last_];
      if (code == 1) {  // the regular case: the same difference again
        times_[last_] = Plus(times_[last_], ic_.Decompress(last_diff, 1));
        extremes_[last_] = 0;
      } else if (code < kCodeFull) {
        int32_t diff;
        if (code == 0) {
          diff = ic_.Decompress(0, 7);
          count_extreme(diff);
        } else if (code < static_cast<uint32_t>(kMulti)) {
          const auto multi = static_cast<int32_t>(code);
          diff = ic_.Decompress(Times(multi, last_diff), multi < 10 ? 2 : 3);
        } else if (code == static_cast<uint32_t>(kMulti)) {
          diff = ic_.Decompress(Times(kMulti, last_diff), 4);
          count_extreme(diff);
        } else {
          const int32_t multi = kMulti - static_cast<int32_t>(code);  // -1..-10
          if (multi > kMultiMinus) {
            diff = ic_.Decompress(Times(multi, last_diff), 5);
          } else {
            diff = ic_.Decompress(Times(kMultiMinus, last_diff), 6);
            count_extreme(diff);
          }
        }
        times_[last_] = Plus(times_[last_], diff);
      } else if (code == kCodeFull) {
        start_sequence();
      } else {  // 512..514: another sequence, then its own code
        last_ = (last_ + code - kCodeFull) & 3;
        continue;
      }
    }
    time = times_[last_];
    return true;
  }
  return false;
}

}  // namespace pointdag::laz
