// The colors section coded as the hierarchical colors (codec 8, with the voxels' Morton codes: a
// dense block): input = 3-byte voxel count + payload (color_fuzz_input.h).
#include "color_fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  pointdag::fuzz::DecodeColorSection(pointdag::ColorCodec::kHierarchical, data, size, /*morton=*/true);
  return 0;
}
