// RGB14 and RGBNIR14 of LASzip's layered compressor (items version 3 and 4): the colour of LAS 1.4
// point formats 7 and 8 (three uint16), and for RGBNIR14 the near infrared (a fourth uint16) in a
// layer of its own. Each byte of a channel is coded as a correction to a prediction from the last
// colour (green and blue also from how red changed), as LASzip's RGB12 v2 does.
//
// Contract: reads only the layers given to Start(); a layer that runs out decodes zeros and is
// reported by status() (Truncated).
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "pointdag/read/laz/layered_item_decoder.h"

namespace pointdag::laz {

class Rgb14Decoder {
 public:
  // nir: RGBNIR14 (8 bytes, 2 layers) rather than RGB14 (6 bytes, 1 layer).
  Rgb14Decoder(bool nir, uint16_t version);
  ~Rgb14Decoder();
  Rgb14Decoder(const Rgb14Decoder&) = delete;
  Rgb14Decoder& operator=(const Rgb14Decoder&) = delete;

  uint32_t layer_count() const { return nir_ ? 2 : 1; }
  uint32_t size() const { return nir_ ? 8 : 6; }
  // Starts a chunk from the first point's raw item and layer_count() layers, in `context`.
  void Start(const uint8_t* first, const LayerSpan* layers, uint32_t context);
  // Decodes the next point's item in the context POINT14 handed over.
  void Decode(uint8_t* item, uint32_t context);
  Status status() const;

 private:
  struct Models;
  using Values = std::array<uint16_t, 4>;  // red, green, blue, near infrared

  void InitContext(uint32_t context, uint32_t from);

  bool nir_;
  ContextFollower follower_;
  Layer rgb_, nir_layer_;
  std::array<std::unique_ptr<Models>, kScannerChannels> models_;  // created on first use, kept
  std::array<Values, kScannerChannels> last_{};
};

}  // namespace pointdag::laz
