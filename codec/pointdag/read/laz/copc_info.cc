#include "pointdag/read/laz/copc_info.h"

#include <set>

#include "pointdag/read/byte_io.h"

namespace pointdag::laz {
namespace {

constexpr size_t kInfoBytes = 160;
constexpr size_t kEntryBytes = 32;

std::string Num(uint64_t v) { return std::to_string(v); }

}  // namespace

CopcHierarchy ReadCopcHierarchy(const std::vector<unsigned char>& info, const uint8_t* file, uint64_t file_size,
                                uint64_t point_count) {
  CopcHierarchy h;
  if (info.size() < kInfoBytes) {
    h.problem = "the COPC info VLR is " + Num(info.size()) + " bytes, not 160";
    return h;
  }
  for (int axis = 0; axis < 3; ++axis) h.center[axis] = LoadLE<double>(info.data() + 8 * axis);
  h.halfsize = LoadLE<double>(info.data() + 24);
  h.spacing = LoadLE<double>(info.data() + 32);
  const uint64_t root_offset = LoadLE<uint64_t>(info.data() + 40);
  const uint64_t root_size = LoadLE<uint64_t>(info.data() + 48);

  // Pages to visit: (offset, size); each page is read once, whatever the entries claim.
  std::vector<std::pair<uint64_t, uint64_t>> pages{{root_offset, root_size}};
  std::set<uint64_t> seen;
  uint64_t entries_left = file_size / kEntryBytes;  // overlapping pages cannot make the walk quadratic
  while (!pages.empty()) {
    const auto [offset, size] = pages.back();
    pages.pop_back();
    if (offset > file_size || size > file_size - offset || size % kEntryBytes != 0) {
      h.problem = "the COPC hierarchy page at offset " + Num(offset) + " (" + Num(size) +
                  " bytes) lies outside the file of " + Num(file_size) + " bytes";
      break;
    }
    if (!seen.insert(offset).second) {
      h.problem = "the COPC hierarchy lists the page at offset " + Num(offset) + " twice";
      break;
    }
    if (size / kEntryBytes > entries_left) {
      h.problem = "the COPC hierarchy's pages overlap (more entries than the file can hold)";
      break;
    }
    entries_left -= size / kEntryBytes;
    for (uint64_t e = offset; e < offset + size; e += kEntryBytes) {
      const uint8_t* p = file + e;
      CopcNode node{LoadLE<int32_t>(p), LoadLE<int32_t>(p + 4), LoadLE<int32_t>(p + 8), LoadLE<int32_t>(p + 12),
                    LoadLE<uint64_t>(p + 16), LoadLE<int32_t>(p + 24), LoadLE<int32_t>(p + 28)};
      if (node.points == -1) {  // a child page
        pages.emplace_back(node.offset, static_cast<uint64_t>(static_cast<uint32_t>(node.bytes)));
      } else if (node.points > 0) {
        if (node.depth < 0 || node.bytes <= 0 || node.offset > file_size ||
            static_cast<uint64_t>(node.bytes) > file_size - node.offset) {
          h.problem = "COPC node " + Num(static_cast<uint32_t>(node.depth)) + "-" + Num(static_cast<uint32_t>(node.x)) +
                      "-" + Num(static_cast<uint32_t>(node.y)) + "-" + Num(static_cast<uint32_t>(node.z)) +
                      " points outside the file";
          break;
        }
        h.max_depth = std::max(h.max_depth, node.depth);
        h.points += static_cast<uint64_t>(node.points);
        h.nodes.push_back(node);
      }
    }
    if (!h.problem.empty()) break;
  }
  if (h.problem.empty() && h.points != point_count) {
    h.problem = "the COPC hierarchy's nodes hold " + Num(h.points) + " points, the header declares " + Num(point_count);
  }
  if (!h.problem.empty()) {
    h.nodes.clear();
    h.max_depth = -1;
    h.points = 0;
  }
  return h;
}

}  // namespace pointdag::laz
