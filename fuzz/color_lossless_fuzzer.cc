// The colors section coded as the lossless colors (version 1: planar differences in a zstd frame;
// version 2: the context coder, with the voxels' Morton codes): input = 3-byte voxel count + payload
// (color_fuzz_input.h).
#include "color_fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pointdag::fuzz::DecodeColorSection(pointdag::ColorCodec::kLossless, data, size, /*morton=*/true);
  return 0;
}
