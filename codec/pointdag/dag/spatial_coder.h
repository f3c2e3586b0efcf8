// Geometry coder 2 (proto/PDAG_FORMAT.md §2.2): the DAG's symbols range-coded with contexts from
// the true spatial neighbours of each node, as G-PCC's octree coder conditions on its neighbours.
//
// The coder walks the octree level by level in Morton order, over the cells it can know: the
// children of every node coded for the first time (a node's first occurrence is its position), and
// below the last internal level every brick occurrence, new or repeated, with its cells. Each
// cell keeps its six face neighbours on its level, found top-down from its parent's (no search),
// so a child bit is modelled by the children already known next to it on its own level (in the
// lower neighbours, coded before it in Morton order, and its lower siblings) and by the occupancy
// of the parent's neighbours around it. Cells below a repeated internal node are not visited (that
// bounds the walk by the stored DAG, not by the voxels) and count as empty neighbours.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/dag/dag_arrays.h"

namespace pointdag {

// A coded bit costs at least 0.0014 bits and a node mask at least 7 bits (an 8th lone bit is
// implied): a byte of payload holds fewer than 8 / (7 x 0.0014) < 820 nodes.
constexpr uint64_t kMaxSpatialNodesPerByte = 820;

// `version`: the geometry stream's (PDAG_FORMAT §2.2): 2 adds edge and corner neighbours to the
// mask contexts, 1 does without, 3 mixes version 2's model with two more (mask_mixer.h), 4 with
// three more, 5 with five others (mask_mixer5.h), 8 is 5 with young flags, lower starting weights
// and the range coder's compact ends. Returns the payload after the stream's header.
StatusOr<std::vector<uint8_t>> EncodeSpatial(const DagArrays& arrays, int depth, int version);

// `counts`: nodes per internal level, then bricks (the stream's level table, already checked); none
// in version 8, whose decoder bounds the nodes it keeps by `max_nodes` instead.
StatusOr<DagArrays> DecodeSpatial(std::span<const uint8_t> payload, int depth, const std::vector<uint64_t>* counts,
                                  uint64_t max_nodes, int version);

// Geometry stream version 8 (files' default), coder 2's alone: a 2-byte header (the version, then
// the depth in bits 0..4 and the count mode in bit 5) and the payload, without the coder byte and
// the level table of versions 1..6: on small scans those and the range coder's fixed bytes were
// 1 % of the stream. The whole stream, header included.
constexpr int kCompactSpatialVersion = 8;
StatusOr<std::vector<uint8_t>> EncodeCompactSpatial(const DagArrays& arrays, int depth, CountMode mode);
StatusOr<Svdag> DecodeCompactSpatial(std::span<const uint8_t> bytes, uint64_t max_nodes);

}  // namespace pointdag
