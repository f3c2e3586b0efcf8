#include "pointdag/dag/dag_arrays.h"

#include "pointdag/bit_count.h"

namespace pointdag {
namespace {

size_t RecordSize(const Svdag& dag, size_t word) {
  return 1 + static_cast<size_t>(kByteBits[dag.Mask(static_cast<uint32_t>(word))]);
}

}  // namespace

StatusOr<DagArrays> ToArrays(const Svdag& dag) {
  const int levels = dag.internal_levels();
  DagArrays a;
  a.masks.resize(levels);
  a.children.resize(levels);
  a.leaves = dag.leaves;
  // Ordinal of every record start, so references can be told apart as new or repeated.
  std::vector<uint32_t> ordinal(dag.nodes.size(), 0);
  for (int level = 0; level < levels; ++level) {
    uint32_t k = 0;
    for (size_t w = dag.level_offsets[level]; w < dag.level_offsets[level + 1]; w += RecordSize(dag, w)) {
      ordinal[w] = k++;
      a.masks[level].push_back(dag.Mask(static_cast<uint32_t>(w)));
    }
  }
  for (int level = 0; level < levels; ++level) {
    const bool children_are_leaves = level + 1 == levels;
    uint32_t seen = 0;  // nodes of the next level referenced so far
    for (size_t w = dag.level_offsets[level]; w < dag.level_offsets[level + 1]; w += RecordSize(dag, w)) {
      for (int i = 0; i < kByteBits[dag.Mask(static_cast<uint32_t>(w))]; ++i) {
        const uint32_t ref = dag.nodes[w + 1 + i];
        const uint32_t k = children_are_leaves ? ref : ordinal[ref];
        if (k > seen) return Internal("DAG is not in canonical breadth-first order");
        if (k == seen) ++seen;
        a.children[level].push_back(k);
      }
    }
    const size_t next_level = children_are_leaves ? dag.leaves.size() : a.masks[level + 1].size();
    if (seen != next_level) return Internal("DAG holds nodes unreachable from its root");
  }
  return a;
}

StatusOr<Svdag> FromArrays(const DagArrays& a, int depth, CountMode mode) {
  Svdag dag;
  dag.depth = depth;
  dag.mode = mode;
  dag.leaves = a.leaves;
  const int levels = dag.internal_levels();
  // Counts bottom-up, then word addresses and records top-down.
  std::vector<std::vector<uint64_t>> count(levels);
  for (int level = levels - 1; level >= 0; --level) {
    count[level].resize(a.masks[level].size());
    size_t child = 0;
    for (size_t i = 0; i < a.masks[level].size(); ++i) {
      uint64_t sum = mode == CountMode::kMipmap ? 1 : 0;
      for (int c = kByteBits[a.masks[level][i]]; c > 0; --c, ++child) {
        const uint32_t k = a.children[level][child];
        if (level + 1 == levels) {
          sum += mode == CountMode::kMipmap ? BrickMipCount(dag.leaves[k]) : BrickVoxelCount(dag.leaves[k]);
        } else {
          sum += count[level + 1][k];
        }
      }
      count[level][i] = sum;
    }
  }
  std::vector<std::vector<uint32_t>> address(levels);
  uint64_t word = 0;
  for (int level = 0; level < levels; ++level) {
    dag.level_offsets.push_back(static_cast<uint32_t>(word));
    for (uint8_t mask : a.masks[level]) {
      address[level].push_back(static_cast<uint32_t>(word));
      word += 1 + static_cast<uint64_t>(kByteBits[mask]);
      if (word > 0xFFFFFFFFull) return ResourceLimit("decoded DAG exceeds 2^32 node words");
    }
  }
  if (levels > 0) dag.level_offsets.push_back(static_cast<uint32_t>(word));
  dag.nodes.reserve(word);
  for (int level = 0; level < levels; ++level) {
    size_t child = 0;
    for (size_t i = 0; i < a.masks[level].size(); ++i) {
      uint32_t field;
      if (dag.IsUpperLevel(level)) {
        if (count[level][i] > 0xFFFFFFFFull) return ResourceLimit("decoded DAG holds more than 2^32 voxels");
        field = static_cast<uint32_t>(dag.upper_counts.size());
        dag.upper_counts.push_back(static_cast<uint32_t>(count[level][i]));
      } else {
        field = static_cast<uint32_t>(count[level][i]);
      }
      dag.nodes.push_back(uint32_t{a.masks[level][i]} << 24 | field);
      for (int c = kByteBits[a.masks[level][i]]; c > 0; --c, ++child) {
        const uint32_t k = a.children[level][child];
        dag.nodes.push_back(level + 1 == levels ? k : address[level + 1][k]);
      }
    }
  }
  return dag;
}

}  // namespace pointdag
