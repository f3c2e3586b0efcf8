// The colors section coded as Paper IIB's variable-rate block stream (range-coded block table and weights): input = 3-byte voxel count + payload (color_fuzz_input.h).
#include "color_fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pointdag::fuzz::DecodeColorSection(pointdag::ColorCodec::kVariableRate, data, size, /*morton=*/true);  // version 3 needs the voxels
  return 0;
}
