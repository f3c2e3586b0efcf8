#include "pointdag/read/laz/gpstime11_decoder.h"

#include <cstring>

#include "pointdag/read/byte_io.h"

namespace pointdag::laz {
namespace {

// The symbols of the multiplier model: 0..kMulti are multipliers of the last difference,
// kMulti+1..kMulti-kMultiMinus the negative ones, then "unchanged", "new sequence" and three
// "switch to sequence last+i".
constexpr int32_t kMulti = 500;
constexpr int32_t kMultiMinus = -10;
constexpr uint32_t kMultiUnchanged = kMulti - kMultiMinus + 1;
constexpr uint32_t kMultiCodeFull = kMulti - kMultiMinus + 2;
constexpr uint32_t kMultiTotal = kMulti - kMultiMinus + 6;
// After the last difference was 0: 0 unchanged, 1 a 32-bit difference, 2 new sequence, 3..5 switch.
constexpr uint32_t kZeroDiffSymbols = 6;
// An encoder switches sequence at most once per point; allow a little slack, never unbounded.
constexpr int kMaxSwitches = 3;

// LASzip multiplies in 32-bit ints; modulo 2^32 here, which is what its builds compute.
int32_t Times(int32_t multi, int32_t diff) {
  return static_cast<int32_t>(static_cast<uint32_t>(multi) * static_cast<uint32_t>(diff));
}

}  // namespace

Gpstime11Decoder::Gpstime11Decoder(ArithmeticDecoder& decoder)
    : dec_(decoder), multi_model_(kMultiTotal), zero_diff_model_(kZeroDiffSymbols), ic_(decoder, 32, 9) {}

void Gpstime11Decoder::Init(const uint8_t* item) {
  last_ = next_ = 0;
  time_[0] = LoadLE<uint64_t>(item);
  for (int i = 1; i < 4; ++i) time_[i] = 0;
  for (int i = 0; i < 4; ++i) diff_[i] = extreme_count_[i] = 0;
  multi_model_.Reset();
  zero_diff_model_.Reset();
  ic_.Reset();
}

void Gpstime11Decoder::StartSequence() {
  next_ = (next_ + 1) & 3;
  const int32_t high = ic_.Decompress(static_cast<int32_t>(time_[last_] >> 32), 8);
  time_[next_] = (static_cast<uint64_t>(static_cast<uint32_t>(high)) << 32) | dec_.ReadInt();
  last_ = next_;
  diff_[last_] = 0;
  extreme_count_[last_] = 0;
}

void Gpstime11Decoder::AddDiff(int32_t diff, bool extreme) {
  // Differences far from the prediction become the new reference after four in a row.
  if (extreme && ++extreme_count_[last_] > 3) {
    diff_[last_] = diff;
    extreme_count_[last_] = 0;
  }
  time_[last_] += static_cast<uint64_t>(static_cast<int64_t>(diff));
}

bool Gpstime11Decoder::Decode(uint8_t* out) {
  for (int switches = 0;; ++switches) {
    if (switches > kMaxSwitches) return false;
    if (diff_[last_] == 0) {
      const uint32_t multi = dec_.DecodeSymbol(zero_diff_model_);
      if (multi == 1) {
        diff_[last_] = ic_.Decompress(0, 0);
        time_[last_] += static_cast<uint64_t>(static_cast<int64_t>(diff_[last_]));
        extreme_count_[last_] = 0;
      } else if (multi == 2) {
        StartSequence();
      } else if (multi > 2) {
        last_ = (last_ + multi - 2) & 3;
        continue;  // the point is coded against that sequence next
      }
      break;
    }
    const uint32_t multi = dec_.DecodeSymbol(multi_model_);
    const int32_t last_diff = diff_[last_];
    if (multi == 1) {
      time_[last_] += static_cast<uint64_t>(static_cast<int64_t>(ic_.Decompress(last_diff, 1)));
      extreme_count_[last_] = 0;
    } else if (multi == 0) {
      AddDiff(ic_.Decompress(0, 7), true);
    } else if (multi < static_cast<uint32_t>(kMulti)) {
      const int32_t factor = static_cast<int32_t>(multi);
      AddDiff(ic_.Decompress(Times(factor, last_diff), multi < 10 ? 2 : 3), false);
    } else if (multi == static_cast<uint32_t>(kMulti)) {
      AddDiff(ic_.Decompress(Times(kMulti, last_diff), 4), true);
    } else if (multi < kMultiUnchanged) {
      const int32_t factor = kMulti - static_cast<int32_t>(multi);  // -1 .. kMultiMinus
      if (factor > kMultiMinus) {
        AddDiff(ic_.Decompress(Times(factor, last_diff), 5), false);
      } else {
        AddDiff(ic_.Decompress(Times(kMultiMinus, last_diff), 6), true);
      }
    } else if (multi == kMultiCodeFull) {
      StartSequence();
    } else if (multi > kMultiCodeFull) {
      last_ = (last_ + multi - kMultiCodeFull) & 3;
      continue;
    }
    break;  // kMultiUnchanged: the same time again
  }
  std::memcpy(out, &time_[last_], 8);
  return true;
}

}  // namespace pointdag::laz
