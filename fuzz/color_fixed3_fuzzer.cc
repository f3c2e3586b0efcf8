// The colors section coded as Paper IIA's fixed-rate block stream (3-bit weights): input = 3-byte voxel count + payload (color_fuzz_input.h).
#include "color_fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pointdag::fuzz::DecodeColorSection(pointdag::ColorCodec::kFixedRate, data, size, /*morton=*/true);  // version 3 needs the voxels
  return 0;
}
