// The stored DAG stream alone (all four coders: the second byte picks one; coder 3 in versions 6 and 7), as DecodePdag runs it for a
// tile: nodes bounded as for a 2^24-voxel tile. A stream that decodes must re-encode to a stream
// that decodes to the same DAG (or, for coder 2, be refused as storing a brick twice). EncodeDag
// validates first, so a decoded DAG that Validate rejects aborts too: DecodeDag no longer runs
// Validate after coders 0, 1 and 3, whose arrays are valid by construction.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "pointdag/dag/dag_stream.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto dag = pointdag::DecodeDag(std::span<const uint8_t>(data, size), uint64_t{1} << 20);
  if (!dag.ok()) return 0;
  for (auto coder : {pointdag::GeometryCoder::kZstd, pointdag::GeometryCoder::kContext, pointdag::GeometryCoder::kSpatial,
                     pointdag::GeometryCoder::kTable}) {
    const int version = coder == pointdag::GeometryCoder::kTable ? pointdag::kTableStreamVersion : pointdag::kGeometryStreamVersion;
    const auto again = pointdag::EncodeDag(*dag, coder, version);
    // Coder 2 refuses, by contract, a DAG that stores a brick twice (which coders 0 and 1 can carry).
    if (coder == pointdag::GeometryCoder::kSpatial && again.status().code() == pointdag::StatusCode::kInvalidArgument) continue;
    if (!again.ok() || !(pointdag::DecodeDag(*again).value() == *dag)) std::abort();
  }
  const auto refs = pointdag::EncodeDag(*dag, pointdag::GeometryCoder::kTable, pointdag::kPrefixRefsStreamVersion);
  if (!refs.ok() || !(pointdag::DecodeDag(*refs).value() == *dag)) std::abort();
  return 0;
}
