#include "pointdag/read/laz/layered_chunk_decoder.h"

namespace pointdag::laz {

StatusOr<std::unique_ptr<ChunkDecoder>> MakeLayeredChunkDecoder(const LaszipVlr&) {
  return Unsupported("the LAZ layered chunk decoder is not written yet");
}

}  // namespace pointdag::laz
