// Stage 4c: the compact stored form of an SVDAG (files and the wire), paired encoder/decoder.
//
// The resident DAG spends 4 bytes per child pointer; on sampled scans few subtrees repeat, so the
// pointers dominate (13.8 bits/voxel on lion at 1 cm). The stored form drops them: nodes are
// written breadth-first in the resident DAG's canonical first-seen order, so a child that is seen
// for the first time is implicitly "the next node of the next level", and only children that
// repeat an earlier subtree carry a flag and a back-reference (the earlier node's ordinal). Leaf
// bricks are written as a 2x2x2 cell mask plus one voxel mask per occupied cell, i.e. as the two
// octree levels they stand for. Counts are not stored: the decoder recomputes them bottom-up.
//
// Three entropy back-ends (normative layout: proto/PDAG_FORMAT.md):
// - kZstd: masks, flags and references in separate byte streams, each compressed with zstd -19;
// - kContext: one adaptive binary range coder; each mask bit's probability is conditioned on the
//   node's height and on the mask bits already coded (a bit-tree per height), flags on the height;
// - kSpatial (the default): the range coder with contexts from each node's spatial neighbours,
//   bricks coded at every occurrence and merged by the decoder (spatial_coder.h); stream version 3
//   mixes three models per mask bit (mask_mixer.h), version 4 five, version 5 five others with a
//   secondary estimate (mask_mixer5.h) and codes the nodes of heights 3 and 4 at every occurrence
//   too (slot_merge.h); decoding about 6x slower than kContext;
// - kTable (stream versions 6 and 7, tiles): the symbols of kZstd and kContext, each mask by table
//   lookup in a prefix code per height, flags range-coded, references range-coded (6) or prefix-coded
//   (7) (table_coder.h).
// DecodeDag() runs in linear time (in the stored DAG plus its brick occurrences) and returns the
// identical resident DAG.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/dag/svdag.h"

namespace pointdag {

enum class GeometryCoder : uint8_t { kZstd = 0, kContext = 1, kSpatial = 2, kTable = 3 };
const char* GeometryCoderName(GeometryCoder coder);

// The stream version writers write (PDAG_FORMAT §2.2): 8, coder 2's alone (spatial_coder.h: its
// own 2-byte header, no level table; coders 0 and 1 asked for it write version 5, as their streams
// are the same in 1..5). 1..5 stay readable and writable: they differ only in coder 2, version 3's
// costing 1.6x the decode time of version 2's, version 4's 1.2x version 3's, version 5's 1.2x
// version 4's.
constexpr int kGeometryStreamVersion = 8;
// Versions 6 and 7 are coder 3's, and coder 3 is theirs: readers read 1..8.
constexpr int kTableStreamVersion = 6;
// Version 7 (the tiles'): coder 3 with its references in the prefix section (table_coder.h).
constexpr int kPrefixRefsStreamVersion = 7;
constexpr bool IsTableVersion(int version) { return version == kTableStreamVersion || version == kPrefixRefsStreamVersion; }

// `version`: 1..kGeometryStreamVersion for coders 0..2, kTableStreamVersion or kPrefixRefsStreamVersion for kTable.
StatusOr<std::vector<uint8_t>> EncodeDag(const Svdag& dag, GeometryCoder coder, int version = kGeometryStreamVersion);

// `max_nodes` bounds what a lying header may make the decoder allocate (nodes + bricks).
StatusOr<Svdag> DecodeDag(std::span<const uint8_t> bytes, uint64_t max_nodes = uint64_t{1} << 32);

}  // namespace pointdag
