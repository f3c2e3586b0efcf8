// Decodes the point records of one LAZ chunk back to the exact LAS record bytes.
//
// Contract: a ChunkDecoder reads only the chunk's own bytes. Start() takes them (as the chunk
// table bounds them, or the rest of the point data when a file has no table) and how many points
// the chunk holds; Decode() then fills n complete records at a time, in order. Any inconsistency
// (the stream ends early, a layer's size lies, a value a real encoder cannot produce) is a
// Truncated or Malformed status; the caller names the chunk. Decoders keep no global state, so one
// per thread decodes chunks in parallel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "pointdag/read/laz/laszip_vlr.h"
#include "pointdag/status.h"

namespace pointdag::laz {

class ChunkDecoder {
 public:
  virtual ~ChunkDecoder() = default;
  // Begins a chunk of `points` records stored in [data, data + size).
  virtual Status Start(const uint8_t* data, size_t size, uint64_t points) = 0;
  // Decodes the next n records (n <= the points left in the chunk) into out: n * record_length bytes.
  virtual Status Decode(uint8_t* out, size_t n) = 0;
  // Once every point of the chunk is decoded: how many bytes of `data` the chunk used, i.e. where
  // the next chunk starts in a file without a chunk table.
  virtual size_t BytesUsed() const = 0;
};

// The decoder for the VLR's compressor and items (point-wise v2 items, or layered v3 items).
StatusOr<std::unique_ptr<ChunkDecoder>> MakeChunkDecoder(const LaszipVlr& vlr);

}  // namespace pointdag::laz
