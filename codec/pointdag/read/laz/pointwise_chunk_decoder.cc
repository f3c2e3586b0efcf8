#include "pointdag/read/laz/pointwise_chunk_decoder.h"

namespace pointdag::laz {

StatusOr<std::unique_ptr<ChunkDecoder>> MakePointwiseChunkDecoder(const LaszipVlr&) {
  return Unsupported("the LAZ pointwise chunk decoder is not written yet");
}

}  // namespace pointdag::laz
