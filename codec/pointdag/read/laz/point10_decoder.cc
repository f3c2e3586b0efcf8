#include "pointdag/read/laz/point10_decoder.h"

#include <cstring>

#include "pointdag/read/byte_io.h"

namespace pointdag::laz {
namespace {

// LASzip's contexts for a return r of n returns: m selects the intensity and x/y-difference
// predictors, l the height predictor. Rows n, columns r; the "impossible" pairs (r > n, zeros)
// get contexts of their own because real files contain them.
constexpr uint8_t kReturnMap[8][8] = {
    {15, 14, 13, 12, 11, 10, 9, 8}, {14, 0, 1, 3, 6, 10, 10, 9},      {13, 1, 2, 4, 7, 11, 11, 10},
    {12, 3, 4, 5, 8, 12, 12, 11},   {11, 6, 7, 8, 9, 13, 13, 12},     {10, 10, 11, 12, 13, 14, 14, 13},
    {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15},
};
constexpr uint8_t kReturnLevel[8][8] = {
    {0, 1, 2, 3, 4, 5, 6, 7}, {1, 0, 1, 2, 3, 4, 5, 6}, {2, 1, 0, 1, 2, 3, 4, 5}, {3, 2, 1, 0, 1, 2, 3, 4},
    {4, 3, 2, 1, 0, 1, 2, 3}, {5, 4, 3, 2, 1, 0, 1, 2}, {6, 5, 4, 3, 2, 1, 0, 1}, {7, 6, 5, 4, 3, 2, 1, 0},
};

// Bits of the "changed" symbol: which fields differ from the previous point.
constexpr uint32_t kReturnBitsChanged = 32, kIntensityChanged = 16, kClassificationChanged = 8,
                   kScanAngleChanged = 4, kUserDataChanged = 2, kPointSourceIdChanged = 1;

// A coordinate context from a correction's bit length: even lengths below `cap`, else `cap`.
uint32_t BitsContext(uint32_t k, uint32_t cap) { return k < cap ? (k & ~1U) : cap; }

}  // namespace

Point10Decoder::Point10Decoder(ArithmeticDecoder& decoder)
    : dec_(decoder),
      intensity_ic_(decoder, 16, 4),
      point_source_id_ic_(decoder, 16),
      dx_ic_(decoder, 32, 2),
      dy_ic_(decoder, 32, 22),
      z_ic_(decoder, 32, 20) {}

void Point10Decoder::Init(const uint8_t* item) {
  x_ = LoadLE<uint32_t>(item);
  y_ = LoadLE<uint32_t>(item + 4);
  z_ = LoadLE<uint32_t>(item + 8);
  intensity_ = 0;  // LASzip starts the intensity over at 0, not at the first point's
  return_bits_ = item[14];
  classification_ = item[15];
  scan_angle_ = item[16];
  user_data_ = item[17];
  point_source_id_ = LoadLE<uint16_t>(item + 18);

  for (uint16_t& v : last_intensity_) v = 0;
  for (int32_t& v : last_height_) v = 0;
  for (Median5& m : x_diff_) m.Reset();
  for (Median5& m : y_diff_) m.Reset();
  changed_.Reset();
  for (ArithmeticModel& m : scan_angle_models_) m.Reset();
  return_bits_models_.Reset();
  classification_models_.Reset();
  user_data_models_.Reset();
  intensity_ic_.Reset();
  point_source_id_ic_.Reset();
  dx_ic_.Reset();
  dy_ic_.Reset();
  z_ic_.Reset();
}

void Point10Decoder::Decode(uint8_t* out) {
  const uint32_t changed = dec_.DecodeSymbol(changed_);
  if (changed & kReturnBitsChanged) {
    return_bits_ = static_cast<uint8_t>(dec_.DecodeSymbol(return_bits_models_.Get(return_bits_)));
  }
  const uint32_t r = return_bits_ & 7U;
  const uint32_t n = (return_bits_ >> 3) & 7U;
  const uint32_t m = kReturnMap[n][r];
  const uint32_t l = kReturnLevel[n][r];
  // With no change flagged at all, the intensity stays the previous point's (LASzip's quirk).
  if (changed != 0) {
    if (changed & kIntensityChanged) {
      intensity_ = static_cast<uint16_t>(intensity_ic_.Decompress(last_intensity_[m], m < 3 ? m : 3));
      last_intensity_[m] = intensity_;
    } else {
      intensity_ = last_intensity_[m];
    }
    if (changed & kClassificationChanged) {
      classification_ = static_cast<uint8_t>(dec_.DecodeSymbol(classification_models_.Get(classification_)));
    }
    if (changed & kScanAngleChanged) {
      const uint32_t direction = (return_bits_ >> 6) & 1U;
      scan_angle_ = static_cast<uint8_t>(scan_angle_ + dec_.DecodeSymbol(scan_angle_models_[direction]));
    }
    if (changed & kUserDataChanged) {
      user_data_ = static_cast<uint8_t>(dec_.DecodeSymbol(user_data_models_.Get(user_data_)));
    }
    if (changed & kPointSourceIdChanged) {
      point_source_id_ = static_cast<uint16_t>(point_source_id_ic_.Decompress(point_source_id_));
    }
  }

  const uint32_t single = n == 1 ? 1 : 0;
  const int32_t dx = dx_ic_.Decompress(x_diff_[m].Get(), single);
  x_ += static_cast<uint32_t>(dx);
  x_diff_[m].Add(dx);

  const int32_t dy = dy_ic_.Decompress(y_diff_[m].Get(), single + BitsContext(dx_ic_.k(), 20));
  y_ += static_cast<uint32_t>(dy);
  y_diff_[m].Add(dy);

  const uint32_t k = (dx_ic_.k() + dy_ic_.k()) / 2;
  last_height_[l] = z_ic_.Decompress(last_height_[l], single + BitsContext(k, 18));
  z_ = static_cast<uint32_t>(last_height_[l]);

  std::memcpy(out, &x_, 4);
  std::memcpy(out + 4, &y_, 4);
  std::memcpy(out + 8, &z_, 4);
  std::memcpy(out + 12, &intensity_, 2);
  out[14] = return_bits_;
  out[15] = classification_;
  out[16] = scan_angle_;
  out[17] = user_data_;
  std::memcpy(out + 18, &point_source_id_, 2);
}

}  // namespace pointdag::laz
