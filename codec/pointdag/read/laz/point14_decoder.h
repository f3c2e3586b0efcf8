// POINT14 of LASzip's layered compressor (items version 3 and 4): the 30-byte core of LAS 1.4
// point formats 6-10, in nine layers (returns and X/Y with the scanner channel, Z, classification,
// flags, intensity, scan angle, user data, point source, GPS time).
//
// Each scanner channel has its own context (models and last values); the point says when the
// channel changes. POINT14 hands the context to the items after it: version 4 always the point's
// context, version 3 (as LASzip 3.x's reader did) 0 except at a point whose channel changed.
//
// Contract: reads only the layers given to Start(); a layer that runs out decodes zeros and is
// reported by status() (Truncated), as is a GPS time no encoder writes (Malformed). Every index
// into a table comes from a masked field or a model's symbol range, so no input leads outside one.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "pointdag/read/laz/layered_item_decoder.h"

namespace pointdag::laz {

class Point14Decoder {
 public:
  static constexpr uint32_t kLayers = 9;
  static constexpr uint32_t kSize = 30;

  explicit Point14Decoder(uint16_t version);
  ~Point14Decoder();
  Point14Decoder(const Point14Decoder&) = delete;
  Point14Decoder& operator=(const Point14Decoder&) = delete;

  // Starts a chunk from its raw first point (kSize bytes) and its kLayers layers; returns the
  // context for the items after POINT14.
  uint32_t Start(const uint8_t* first, const LayerSpan* layers);
  // Decodes the next point into item[0, kSize); `context` (0 on entry) becomes the context for
  // the items after POINT14.
  void Decode(uint8_t* item, uint32_t& context);
  // What went wrong since Start(), if anything.
  Status status() const;

  // The fields LASzip predicts from (the record's bit fields apart).
  struct Fields {
    int32_t x = 0, y = 0, z = 0;
    uint16_t intensity = 0;
    uint8_t return_number = 0, number_of_returns = 0;  // 4 bits each
    uint8_t flags = 0;  // classification flags (bits 0-3), scan direction (4), edge of flight line (5)
    uint8_t scanner_channel = 0;
    uint8_t classification = 0, user_data = 0;
    uint16_t scan_angle = 0;  // int16 in the record, kept as its bits
    uint16_t point_source = 0;
    uint64_t gps_time = 0;  // the double's bits
    bool gps_time_change = false;
  };

 private:
  struct Context;
  enum LayerIndex { kXY, kZ, kClassification, kFlags, kIntensity, kScanAngle, kUserData, kPointSource, kGpsTime };

  Context& InitContext(uint32_t channel, const Fields& from);

  uint16_t version_;
  std::array<Layer, kLayers> layers_;
  std::array<std::unique_ptr<Context>, kScannerChannels> contexts_;  // created on first use, kept
  std::array<bool, kScannerChannels> used_{};                        // in this chunk
  uint32_t current_ = 0;
  bool bad_gps_time_ = false;
};

}  // namespace pointdag::laz
