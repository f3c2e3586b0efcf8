// LAZ bytes from outside through OpenScan: the LAS header, the LASzip VLR, the chunk table, the
// COPC index, then every chunk decoded (in parallel windows) and surveyed (scan_file_fuzz.h).
// Seeds: laz-perf's point10-1.0.laz (Apache-2.0) and laspy's 1_4_w_evlr.laz (BSD-2-Clause), as
// in ../shared/data/laz; scripts/fuzz adds every file of that folder to the corpus.
#include "scan_file_fuzz.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return pointdag::fuzz::FuzzScanFile("laz", data, size);
}
