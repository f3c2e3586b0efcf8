// Stand-ins for the color decoders the WebAssembly build leaves out: the image-mapped ones (libpng/TurboJPEG/
// libwebp and astcenc are not built for emscripten) and the hierarchical colors (never in tiles).
// decode_tile_wasm.cc refuses those codecs before decoding, so these only keep the real DecodeColors
// (color/color_decode.cc) linkable.
#include "pointdag/color/astc_mapping.h"
#include "pointdag/color/hierarchical_colors.h"
#include "pointdag/color/image_mapping.h"

namespace pointdag {

StatusOr<std::vector<Rgb8>> DecodeColorImage(std::span<const uint8_t>, uint64_t) {
  return Unsupported("png, jpeg and webp colors are not in the WebAssembly build");
}

StatusOr<std::vector<Rgb8>> DecodeColorAstc(std::span<const uint8_t>, uint64_t) {
  return Unsupported("astc colors are not in the WebAssembly build");
}

StatusOr<std::vector<Rgb8>> DecodeHierarchicalColors(std::span<const uint8_t>, uint64_t, std::span<const uint64_t>) {
  return Unsupported("hierarchical colors are not in the WebAssembly build");
}

}  // namespace pointdag
