// Chunks of LASzip's layered chunked compressor (LAS 1.4 point formats 6-8): POINT14, RGB14, RGBNIR14, BYTE14 items, versions 3 and 4.
//
// A chunk is the first record raw, the chunk's point count (uint32), the byte size of every layer
// (uint32 each: POINT14's nine, then RGB14's one or RGBNIR14's two, then one per extra byte), then
// the layers' bytes in that order. Start() checks that the layers fit in the chunk before any is
// read, and that the count is the caller's; BytesUsed() is known as soon as Start() succeeds.
//
// Versions 3 and 4 decode the same streams except in how a point's scanner channel selects the
// colour and extra-byte contexts (see layered_item_decoder.h and point14_decoder.h).
#pragma once

#include <memory>

#include "pointdag/read/laz/chunk_decoder.h"

namespace pointdag::laz {

// The VLR has passed ParseLaszipVlr(): its items are ones this decoder knows. Items must come in
// the order LASzip writes them: POINT14, then RGB14 or RGBNIR14, then BYTE14 (Malformed otherwise).
StatusOr<std::unique_ptr<ChunkDecoder>> MakeLayeredChunkDecoder(const LaszipVlr& vlr);

}  // namespace pointdag::laz
