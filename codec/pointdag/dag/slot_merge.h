// Geometry coder 2 codes the nodes of its *slot levels* at every occurrence instead of behind
// back-references (proto/PDAG_FORMAT.md §2.2): the bricks in every version, and from version 5 the
// nodes of heights 3 and 4 too. The encoder walks a copy of the DAG's arrays in which those levels are a tree;
// the decoder decodes that tree and merges equal nodes bottom-up back into the DAG, numbered in the
// order first seen, which is the canonical order, so the resident DAG is the one that was encoded.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "pointdag/dag/dag_arrays.h"

namespace pointdag {

// The first level whose nodes are slots: D − 2 (the bricks) before version 5, from it the nodes of
// heights 3 and 4 too (D − 4; never the root: levels = D − 2 internal levels). Measured, version 5
// otherwise equal: height 3 alone −0.7..−5 % (tiny: refs and flags were a third of its stream),
// height 4 too another −0.03..−0.3 % (tiny −1.7 %); higher ones repeat too rarely on any scan.
constexpr int SlotLevel(int levels, int version) { return version >= 5 && levels >= 2 ? std::max(levels - 2, 1) : levels; }

// Whether every node of the internal levels from `slot_level` on is stored once (as the builder's
// DAG stores it): the decoder merges equal ones, so only then does the same DAG come back. (One
// decoded from a hostile stream of an older version or another coder may repeat a node.)
bool SlotsStoredOnce(const DagArrays& arrays, int slot_level);

// The encoder's view: `arrays` with the internal levels from `slot_level` on copied per occurrence
// (their child ordinals then count up from 0 on every level; the bricks stay as they are).
DagArrays ExpandSlots(const DagArrays& arrays, int slot_level);

// The decoder's merge: `slots` holds the 64-bit value of every brick slot in order, `a` the decoded
// tree of the internal slot levels; equal bricks, then equal nodes of each internal slot level from
// the bottom up, become one. Every level's distinct count must equal the header's `counts` (none
// in version 8: as many as there are).
Status MergeSlots(DagArrays& a, const std::vector<uint64_t>& slots, const std::vector<uint64_t>* counts, int slot_level);

}  // namespace pointdag
