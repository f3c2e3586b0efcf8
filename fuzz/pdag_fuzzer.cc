// .pdag bytes from outside (a tile from a server, a file from a user): the container, then the
// whole decoder behind it (metadata, stored DAG, colors), exactly as `pointdag decode` runs them.
// A mutated file almost never keeps its CRCs, which would keep the fuzzer out of everything behind
// them; so the input is also run a second time with its CRCs recomputed.
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "pointdag/container/crc32c.h"
#include "pointdag/pipeline.h"
#include "pointdag/read/byte_io.h"

namespace {

// The input with every CRC made to match (sections that lie outside the file are left as they are).
std::vector<uint8_t> WithCrcsFixed(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  if (size < 32) return bytes;
  const uint32_t count = pointdag::LoadLE<uint32_t>(bytes.data() + 12);
  if (count == 0 || count > 64 || size < 32 + 32 * size_t{count}) return bytes;
  for (uint32_t i = 0; i < count; ++i) {
    uint8_t* e = bytes.data() + 32 + 32 * i;
    const uint64_t offset = pointdag::LoadLE<uint64_t>(e + 8), length = pointdag::LoadLE<uint64_t>(e + 16);
    if (offset > size || length > size - offset) continue;
    const uint32_t crc = pointdag::Crc32c(std::span<const uint8_t>(bytes.data() + offset, length));
    std::memcpy(e + 24, &crc, 4);
  }
  std::vector<uint8_t> head(bytes.begin(), bytes.begin() + 32 + 32 * static_cast<long>(count));
  std::memset(head.data() + 16, 0, 4);
  const uint32_t crc = pointdag::Crc32c(head);
  std::memcpy(bytes.data() + 16, &crc, 4);
  return bytes;
}

void Decode(std::span<const uint8_t> bytes) {
  // A tile's bounds: what a fuzzer's 2 GB may hold, and what `pointdag fetch` allows a tile.
  pointdag::DecodeLimits limits;
  limits.max_voxels = uint64_t{1} << 20;
  limits.max_nodes = uint64_t{1} << 20;
  auto file = pointdag::ParsePdag(bytes);
  if (file.ok()) (void)pointdag::DecodePdag(*file, limits);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Decode(std::span<const uint8_t>(data, size));
  Decode(WithCrcsFixed(data, size));
  return 0;
}
