// Chunks of LASzip's layered chunked compressor (LAS 1.4 point formats 6-8): POINT14, RGB14, RGBNIR14, BYTE14 items, versions 3 and 4.
#pragma once

#include <memory>

#include "pointdag/read/laz/chunk_decoder.h"

namespace pointdag::laz {

// The VLR has passed ParseLaszipVlr(): its items are ones this decoder knows.
StatusOr<std::unique_ptr<ChunkDecoder>> MakeLayeredChunkDecoder(const LaszipVlr& vlr);

}  // namespace pointdag::laz
