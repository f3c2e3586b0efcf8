// The 2D image mapping's payload (curve, format, side, then PNG/JPEG/WebP bytes that reach
// libpng / TurboJPEG / libwebp after our own checks): input = 3-byte voxel count + payload (color_fuzz_input.h).
#include "color_fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // The codec byte only routes; the payload names its own format, so PNG stands for all three.
  pointdag::fuzz::DecodeColorSection(pointdag::ColorCodec::kPng, data, size);
  return 0;
}
