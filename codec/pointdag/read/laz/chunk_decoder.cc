#include "pointdag/read/laz/chunk_decoder.h"

#include "pointdag/read/laz/layered_chunk_decoder.h"
#include "pointdag/read/laz/pointwise_chunk_decoder.h"

namespace pointdag::laz {

StatusOr<std::unique_ptr<ChunkDecoder>> MakeChunkDecoder(const LaszipVlr& vlr) {
  if (vlr.compressor == Compressor::kLayeredChunked) return MakeLayeredChunkDecoder(vlr);
  return MakePointwiseChunkDecoder(vlr);
}

}  // namespace pointdag::laz
