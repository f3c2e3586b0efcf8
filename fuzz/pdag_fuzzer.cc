// .pdag bytes from outside (a tile from a server, a file from a user): the container, then the
// whole decoder behind it (metadata, stored DAG, colors), exactly as `pointdag decode` runs them.
#include <cstdint>
#include <span>

#include "pointdag/pipeline.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto file = pointdag::ParsePdag(std::span<const uint8_t>(data, size));
  if (file.ok()) (void)pointdag::DecodePdag(*file);
  return 0;
}
