// The colors section coded as the lossless colors (planar differences in a zstd frame): input = 3-byte voxel count + payload (color_fuzz_input.h).
#include "color_fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pointdag::fuzz::DecodeColorSection(pointdag::ColorCodec::kLossless, data, size);
  return 0;
}
