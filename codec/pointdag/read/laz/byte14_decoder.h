// BYTE14 of LASzip's layered compressor (items version 3 and 4): a LAS 1.4 record's extra bytes,
// each byte in a layer of its own, coded as its difference to the last point's byte (mod 256).
//
// Contract: reads only the layers given to Start(); a layer that runs out decodes zeros and is
// reported by status() (Truncated).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "pointdag/read/laz/layered_item_decoder.h"

namespace pointdag::laz {

class Byte14Decoder {
 public:
  // count: the extra bytes per record (1..65535, the VLR item's size).
  Byte14Decoder(uint32_t count, uint16_t version);

  uint32_t layer_count() const { return count_; }
  uint32_t size() const { return count_; }
  // Starts a chunk from the first point's raw item and count layers, in `context`.
  void Start(const uint8_t* first, const LayerSpan* layers, uint32_t context);
  // Decodes the next point's item in the context POINT14 handed over.
  void Decode(uint8_t* item, uint32_t context);
  Status status() const;

 private:
  void InitContext(uint32_t context, uint32_t from);

  uint32_t count_;
  ContextFollower follower_;
  std::vector<Layer> layers_;
  std::vector<uint32_t> changed_;  // indices of the non-empty layers
  std::vector<LazyModels> models_;  // per context; only non-empty layers ever create theirs
  std::array<std::vector<uint8_t>, kScannerChannels> last_;
};

}  // namespace pointdag::laz
