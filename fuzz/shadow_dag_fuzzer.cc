// A shadow DAG file from outside (proto/SHADOW_FORMAT.md §1): ShadowDag::Deserialize, then queries
// all over the grid. A mutated file almost never keeps its CRC, which would keep the fuzzer out of
// the structure checks; so the input is also run a second time with the CRC recomputed. What
// decodes must re-serialize to the same bytes.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "pointdag/container/crc32c.h"
#include "pointdag/shadow/shadow_dag.h"

namespace {

void Decode(std::span<const uint8_t> bytes) {
  const auto dag = pointdag::ShadowDag::Deserialize(bytes);
  if (!dag.ok()) return;
  const double side = static_cast<double>(bytes[6] < 22 ? uint32_t{1} << bytes[6] : 1);
  for (int i = 0; i <= 64; ++i) {
    const double t = side * i / 64.0;
    (void)dag->Shadowed({t, side - t, t * 0.37});
  }
  const std::vector<uint8_t> again = dag->Serialize();
  if (again.size() != bytes.size() || std::memcmp(again.data(), bytes.data(), bytes.size()) != 0) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Decode(std::span<const uint8_t>(data, size));
  if (size >= 64) {
    std::vector<uint8_t> fixed(data, data + size);
    const std::span<const uint8_t> view(fixed);
    const uint32_t crc = pointdag::Crc32c(view.subspan(64), pointdag::Crc32c(view.first(60)));
    std::memcpy(fixed.data() + 60, &crc, 4);
    Decode(fixed);
  }
  return 0;
}
