// Chunks of LASzip's point-wise chunked compressor (LAS 1.0-1.3 point formats 0-3 and BYTE extra
// bytes): POINT10, GPSTIME11, RGB12, BYTE items, version 2.
//
// A chunk stores its first point raw (the items' bytes, in order), then one arithmetic-coded
// stream in which every further point is coded item after item; every model starts over at the
// chunk's first point. LASzip's encoder ends the stream with the bytes the decoder reads ahead,
// so the decoder stops exactly at the chunk's end (BytesUsed()).
#pragma once

#include <memory>

#include "pointdag/read/laz/chunk_decoder.h"

namespace pointdag::laz {

// The VLR has passed ParseLaszipVlr(). Unsupported for item lists LASzip does not write (an item
// type twice) and ResourceLimit for a BYTE item over ByteDecoder::kMaxCount bytes.
StatusOr<std::unique_ptr<ChunkDecoder>> MakePointwiseChunkDecoder(const LaszipVlr& vlr);

}  // namespace pointdag::laz
