// COPC (Cloud Optimized Point Cloud) is a LAZ 1.4 file whose chunks are the nodes of an octree,
// indexed by a hierarchy EVLR. The reader decodes it as plain LAZ; this keeps the index as metadata.
//
// Contract: ReadCopcHierarchy() never trusts the info VLR: a hierarchy that points outside the file,
// pages that overlap or loop, or node counts that do not add up leave `problem` set (the file is
// still read as LAZ) instead of failing. Pages are visited at most once and entries are bounded by
// the file size, so a hostile index cannot make it loop or allocate without limit.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace pointdag::laz {

struct CopcNode {
  int32_t depth = 0, x = 0, y = 0, z = 0;  // the octree key
  uint64_t offset = 0;                      // the node's chunk in the file
  int32_t bytes = 0;
  int32_t points = 0;
};

struct CopcHierarchy {
  std::array<double, 3> center{0, 0, 0};
  double halfsize = 0;
  double spacing = 0;
  std::vector<CopcNode> nodes;  // every node with points, in the order the pages list them
  int max_depth = -1;
  uint64_t points = 0;
  std::string problem;  // why the index is not usable; empty when it is
};

// `info` is the 160-byte payload of the "copc" record 1 VLR; `file` the whole file.
CopcHierarchy ReadCopcHierarchy(const std::vector<unsigned char>& info, const uint8_t* file, uint64_t file_size,
                                uint64_t point_count);

}  // namespace pointdag::laz
