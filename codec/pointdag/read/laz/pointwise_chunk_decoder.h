// Chunks of LASzip's point-wise chunked compressor (LAS 1.0-1.3 point formats 0-3 and BYTE extra bytes): POINT10, GPSTIME11, RGB12, BYTE items, version 2.
#pragma once

#include <memory>

#include "pointdag/read/laz/chunk_decoder.h"

namespace pointdag::laz {

// The VLR has passed ParseLaszipVlr(): its items are ones this decoder knows.
StatusOr<std::unique_ptr<ChunkDecoder>> MakePointwiseChunkDecoder(const LaszipVlr& vlr);

}  // namespace pointdag::laz
