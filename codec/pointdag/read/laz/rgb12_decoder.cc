#include "pointdag/read/laz/rgb12_decoder.h"

#include <algorithm>
#include <cstring>

#include "pointdag/read/byte_io.h"

namespace pointdag::laz {
namespace {

// Bits of the "changed" symbol.
constexpr uint32_t kRedLow = 1, kRedHigh = 2, kGreenLow = 4, kGreenHigh = 8, kBlueLow = 16, kBlueHigh = 32,
                   kNotGrey = 64;

int32_t Clamp8(int32_t v) { return std::clamp(v, 0, 255); }

}  // namespace

Rgb12Decoder::Rgb12Decoder(ArithmeticDecoder& decoder) : dec_(decoder), changed_(128) {}

void Rgb12Decoder::Init(const uint8_t* item) {
  for (int i = 0; i < 3; ++i) last_[i] = LoadLE<uint16_t>(item + 2 * i);
  changed_.Reset();
  for (ArithmeticModel& m : diff_) m.Reset();
}

void Rgb12Decoder::Decode(uint8_t* out) {
  const uint32_t changed = dec_.DecodeSymbol(changed_);
  // The byte `shift` (0 low, 8 high) of a channel: the previous one, or the coded correction to
  // `prediction` (a byte value) modulo 256.
  const auto byte = [&](uint32_t flag, int model, int32_t prediction, uint16_t previous, int shift) -> int32_t {
    if ((changed & flag) == 0) return (previous >> shift) & 0xFF;
    return static_cast<int32_t>((dec_.DecodeSymbol(diff_[model]) + static_cast<uint32_t>(prediction)) & 0xFF);
  };
  uint16_t rgb[3];
  const int32_t red_low = byte(kRedLow, 0, last_[0] & 0xFF, last_[0], 0);
  const int32_t red_high = byte(kRedHigh, 1, last_[0] >> 8, last_[0], 8);
  rgb[0] = static_cast<uint16_t>(red_low | (red_high << 8));
  if (changed & kNotGrey) {
    // Green follows red's change; blue follows the mean of red's and green's (C's truncating /).
    int32_t diff = red_low - (last_[0] & 0xFF);
    const int32_t green_low = byte(kGreenLow, 2, Clamp8(diff + (last_[1] & 0xFF)), last_[1], 0);
    const int32_t blue_low =
        byte(kBlueLow, 4, Clamp8((diff + (green_low - (last_[1] & 0xFF))) / 2 + (last_[2] & 0xFF)), last_[2], 0);
    diff = red_high - (last_[0] >> 8);
    const int32_t green_high = byte(kGreenHigh, 3, Clamp8(diff + (last_[1] >> 8)), last_[1], 8);
    const int32_t blue_high =
        byte(kBlueHigh, 5, Clamp8((diff + (green_high - (last_[1] >> 8))) / 2 + (last_[2] >> 8)), last_[2], 8);
    rgb[1] = static_cast<uint16_t>(green_low | (green_high << 8));
    rgb[2] = static_cast<uint16_t>(blue_low | (blue_high << 8));
  } else {
    rgb[1] = rgb[2] = rgb[0];
  }
  std::memcpy(last_, rgb, sizeof(rgb));
  std::memcpy(out, rgb, sizeof(rgb));
}

}  // namespace pointdag::laz
