// The stored DAG's symbols before entropy coding and after decoding: each internal level's masks
// and child ordinals in canonical order (proto/PDAG_FORMAT.md §2.1), and the bricks. Both geometry
// coders (dag_stream.cc, spatial_coder.cc) write from and read into this form; the resident Svdag
// is derived from it (counts bottom-up, word addresses top-down).
#pragma once

#include <cstdint>
#include <vector>

#include "pointdag/dag/svdag.h"

namespace pointdag {

struct DagArrays {
  std::vector<std::vector<uint8_t>> masks;      // per internal level, canonical order
  std::vector<std::vector<uint32_t>> children;  // per internal level: child ordinals on the next level
                                                // (brick indices below the last), node by node
  std::vector<uint64_t> leaves;                 // bricks in canonical order
};

// Fails unless `dag` is in canonical breadth-first order with every node reachable.
StatusOr<DagArrays> ToArrays(const Svdag& dag);

// The resident DAG of decoded arrays (masks non-zero, ordinals in range: the decoders check).
StatusOr<Svdag> FromArrays(const DagArrays& arrays, int depth, CountMode mode);

}  // namespace pointdag
