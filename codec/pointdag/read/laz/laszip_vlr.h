// The LASzip VLR (user "laszip encoded", record 22204): how a LAZ file's point records were
// compressed: the compressor (point-wise or layered, chunked or not), the chunk size, and the
// list of items (POINT10, GPSTIME11, RGB12, BYTE, POINT14, ...) that together make one record.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "pointdag/status.h"

namespace pointdag::laz {

enum class ItemType : uint16_t {
  kByte = 0,
  kShort = 1,
  kInt = 2,
  kLong = 3,
  kFloat = 4,
  kDouble = 5,
  kPoint10 = 6,
  kGpsTime11 = 7,
  kRgb12 = 8,
  kWavepacket13 = 9,
  kPoint14 = 10,
  kRgb14 = 11,
  kRgbNir14 = 12,
  kWavepacket14 = 13,
  kByte14 = 14,
};

struct Item {
  ItemType type;
  uint16_t size;     // bytes of the record this item covers
  uint16_t version;  // 1, 2 (point-wise) or 3, 4 (layered)
};
std::string ItemName(const Item& item);  // "POINT10:20:v2", the manifest's spelling

enum class Compressor : uint16_t { kNone = 0, kPointwise = 1, kPointwiseChunked = 2, kLayeredChunked = 3 };

// Chunk size of files whose chunks each name their own point count in the chunk table (COPC).
constexpr uint32_t kVariableChunkSize = 0xFFFFFFFFU;

struct LaszipVlr {
  Compressor compressor = Compressor::kNone;
  uint16_t coder = 0;  // 0: arithmetic, the only one LASzip defines
  uint8_t version_major = 0, version_minor = 0;
  uint16_t version_revision = 0;
  uint32_t options = 0;
  uint32_t chunk_size = 0;
  std::vector<Item> items;

  bool variable_chunks() const { return chunk_size == kVariableChunkSize; }
  // Sum of the item sizes: must equal the LAS header's point record length.
  uint32_t record_length() const;
};

// Parses and checks the VLR payload: item sizes must match their types, the items must be a
// combination LASzip writes, and the compressor must be one we decode (Unsupported otherwise, with
// the reason in words). `record_length` is the LAS header's.
StatusOr<LaszipVlr> ParseLaszipVlr(const std::vector<unsigned char>& payload, uint32_t record_length);

}  // namespace pointdag::laz
