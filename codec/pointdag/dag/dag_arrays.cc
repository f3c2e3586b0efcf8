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
  const bool mip = mode == CountMode::kMipmap;
  // Counts bottom-up, then word addresses and records top-down. The last internal level's children
  // are bricks, counted from their bits; every other level's from the level below.
  std::vector<std::vector<uint64_t>> count(levels);
  for (int level = levels - 1; level >= 0; --level) {
    const std::vector<uint8_t>& masks = a.masks[level];
    const uint32_t* child = a.children[level].data();
    count[level].resize(masks.size());
    uint64_t* out = count[level].data();
    if (level + 1 == levels) {
      for (size_t i = 0; i < masks.size(); ++i) {
        uint64_t sum = mip ? 1 : 0;
        for (int c = kByteBits[masks[i]]; c > 0; --c) {
          const uint64_t brick = dag.leaves[*child++];
          sum += mip ? BrickMipCount(brick) : BrickVoxelCount(brick);
        }
        out[i] = sum;
      }
    } else {
      const uint64_t* below = count[level + 1].data();
      for (size_t i = 0; i < masks.size(); ++i) {
        uint64_t sum = mip ? 1 : 0;
        for (int c = kByteBits[masks[i]]; c > 0; --c) sum += below[*child++];
        out[i] = sum;
      }
    }
  }
  std::vector<std::vector<uint32_t>> address(levels);
  uint64_t word = 0;
  for (int level = 0; level < levels; ++level) {
    dag.level_offsets.push_back(static_cast<uint32_t>(word));
    address[level].resize(a.masks[level].size());
    for (size_t i = 0; i < a.masks[level].size(); ++i) {
      address[level][i] = static_cast<uint32_t>(word);
      word += 1 + static_cast<uint64_t>(kByteBits[a.masks[level][i]]);
    }
    if (word > 0xFFFFFFFFull) return ResourceLimit("decoded DAG exceeds 2^32 node words");
  }
  if (levels > 0) dag.level_offsets.push_back(static_cast<uint32_t>(word));
  dag.nodes.resize(word);
  uint32_t* node = dag.nodes.data();
  for (int level = 0; level < levels; ++level) {
    const std::vector<uint8_t>& masks = a.masks[level];
    const uint32_t* child = a.children[level].data();
    // The bricks' indices are stored as they are; other children as their records' addresses.
    const uint32_t* child_address = level + 1 == levels ? nullptr : address[level + 1].data();
    const bool upper = dag.IsUpperLevel(level);
    for (size_t i = 0; i < masks.size(); ++i) {
      uint32_t field;
      if (upper) {
        if (count[level][i] > 0xFFFFFFFFull) return ResourceLimit("decoded DAG holds more than 2^32 voxels");
        field = static_cast<uint32_t>(dag.upper_counts.size());
        dag.upper_counts.push_back(static_cast<uint32_t>(count[level][i]));
      } else {
        field = static_cast<uint32_t>(count[level][i]);
      }
      *node++ = uint32_t{masks[i]} << 24 | field;
      for (int c = kByteBits[masks[i]]; c > 0; --c, ++child) *node++ = child_address ? child_address[*child] : *child;
    }
  }
  return dag;
}

}  // namespace pointdag
