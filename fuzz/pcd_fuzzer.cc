// PCD bytes from outside (an upload, a file given to `pointdag encode`) through OpenScan: the header
// checks, then every point read and surveyed (scan_file_fuzz.h).
#include "scan_file_fuzz.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  pointdag::fuzz::LoadPclReader();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return pointdag::fuzz::FuzzScanFile("pcd", data, size);
}
