// A per-tile shadow layer from outside (proto/SHADOW_FORMAT.md §2): DecodeShadowLayer against the
// voxel count its tile declares (the layer's own header field n, so that the count check passes and
// the body is reached). A mutated layer almost never keeps its CRC, so the input is also run a
// second time with the CRC recomputed. What decodes must hold n voxels and round-trip through the
// writer to the same light.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "pointdag/container/crc32c.h"
#include "pointdag/shadow/shadow_layer.h"

namespace {

void Decode(std::span<const uint8_t> bytes) {
  if (bytes.size() < pointdag::kShadowLayerHeaderBytes) {
    (void)pointdag::DecodeShadowLayer(bytes, 1);
    return;
  }
  uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 8, 4);
  n %= 1u << 20;  // a tile holds at most 2^24 voxels; the fuzzer need not allocate that much
  const auto layer = pointdag::DecodeShadowLayer(bytes, n);
  if (!layer.ok()) return;
  if (layer->light.size() != n) std::abort();
  const auto again = pointdag::EncodeShadowLayer(*layer);
  if (!again.ok()) std::abort();
  const auto back = pointdag::DecodeShadowLayer(*again, n);
  if (!back.ok() || back->light != layer->light) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Decode(std::span<const uint8_t>(data, size));
  if (size >= pointdag::kShadowLayerHeaderBytes) {
    std::vector<uint8_t> fixed(data, data + size);
    const uint32_t crc = pointdag::Crc32c(std::span<const uint8_t>(fixed).subspan(pointdag::kShadowLayerHeaderBytes));
    std::memcpy(fixed.data() + 12, &crc, 4);
    Decode(fixed);
  }
  return 0;
}
