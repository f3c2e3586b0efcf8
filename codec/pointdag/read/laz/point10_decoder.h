// LASzip's POINT10 item, version 2 (the 20 bytes of LAS point formats 0-5: x, y, z, intensity,
// return bits, classification, scan angle, user data, point source id).
//
// Contract: Init() takes the chunk's raw first item; each Decode() then reads the next item from
// the chunk's arithmetic stream and writes its 20 bytes. All state lives in the object and is
// re-initialised by Init(), so one decoder serves chunk after chunk without allocating per chunk.
// Every sum wraps modulo 2^32 as LASzip's int arithmetic does in practice, never signed overflow.
#pragma once

#include <cstdint>

#include "pointdag/read/laz/arithmetic_decoder.h"
#include "pointdag/read/laz/integer_decompressor.h"
#include "pointdag/read/laz/median5.h"
#include "pointdag/read/laz/point10_model_table.h"

namespace pointdag::laz {

class Point10Decoder {
 public:
  static constexpr size_t kSize = 20;

  explicit Point10Decoder(ArithmeticDecoder& decoder);
  void Init(const uint8_t* item);
  void Decode(uint8_t* out);

 private:
  ArithmeticDecoder& dec_;

  // The previous point (the fields coded relative to it).
  uint32_t x_ = 0, y_ = 0, z_ = 0;
  uint16_t intensity_ = 0, point_source_id_ = 0;
  uint8_t return_bits_ = 0, classification_ = 0, scan_angle_ = 0, user_data_ = 0;

  // Per return context m (16) and level l (8): the last intensity, height and x/y differences.
  uint16_t last_intensity_[16] = {};
  int32_t last_height_[8] = {};
  Median5 x_diff_[16], y_diff_[16];

  ArithmeticModel changed_{64};
  ArithmeticModel scan_angle_models_[2] = {ArithmeticModel(256), ArithmeticModel(256)};
  Point10ModelTable return_bits_models_, classification_models_, user_data_models_;
  IntegerDecompressor intensity_ic_, point_source_id_ic_, dx_ic_, dy_ic_, z_ic_;
};

}  // namespace pointdag::laz
