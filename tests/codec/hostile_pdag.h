// Hostile .pdag files for the decoder tests, made from the library's own writer: valid CRCs, valid
// framing, lying or hostile content.
#pragma once

#include <cstring>
#include <string>
#include <vector>

#include "pointdag/container/crc32c.h"
#include "pointdag/pipeline.h"
#include "pointdag/read/byte_io.h"

namespace pointdag::testing {

// The solid cube of side 2^depth (8^depth voxels) as a DAG of one node per level: a few hundred
// bytes stored, however many voxels it holds.
inline Svdag DenseCube(int depth) {
  Svdag dag;
  dag.depth = depth;
  const int levels = depth - 2;
  for (int level = 0; level < levels; ++level) {
    dag.level_offsets.push_back(static_cast<uint32_t>(dag.nodes.size()));
    const uint64_t count = uint64_t{1} << (3 * (depth - level));
    uint32_t field = static_cast<uint32_t>(count);
    if (dag.IsUpperLevel(level)) {
      field = static_cast<uint32_t>(dag.upper_counts.size());
      dag.upper_counts.push_back(static_cast<uint32_t>(count));
    }
    dag.nodes.push_back(0xFFu << 24 | field);
    const uint32_t child = level + 1 == levels ? 0 : static_cast<uint32_t>(9 * (level + 1));
    for (int c = 0; c < 8; ++c) dag.nodes.push_back(child);
  }
  dag.level_offsets.push_back(static_cast<uint32_t>(dag.nodes.size()));
  dag.leaves = {~uint64_t{0}};
  return dag;
}

// The metadata DecodePdag needs, for `voxels` voxels on a depth-`depth` grid.
inline nlohmann::json MinimalMeta(uint64_t voxels, int depth) {
  return {{"voxels", voxels}, {"depth", depth}, {"voxel_size", 1.0}, {"origin", {0.0, 0.0, 0.0}}};
}

// A container around raw metadata text (which need not be JSON at all), as SerializePdag frames it.
inline std::vector<uint8_t> RewrapPdag(const std::string& meta_text, const std::vector<uint8_t>& geometry,
                                       const std::vector<uint8_t>& colors = {}) {
  PdagFile file;
  file.meta = {{"x", std::string(meta_text.size(), ' ')}};  // placeholder, same framing code path
  file.geometry = geometry;
  file.colors = colors;
  std::vector<uint8_t> bytes = SerializePdag(file);
  // Replace the meta section (always first) and fix its length, the offsets and both CRCs.
  const uint64_t old_meta = LoadLE<uint64_t>(bytes.data() + 32 + 16);
  const uint64_t meta_at = LoadLE<uint64_t>(bytes.data() + 32 + 8);
  std::vector<uint8_t> out(bytes.begin(), bytes.begin() + static_cast<long>(meta_at));
  out.insert(out.end(), meta_text.begin(), meta_text.end());
  out.insert(out.end(), bytes.begin() + static_cast<long>(meta_at + old_meta), bytes.end());
  const uint32_t sections = LoadLE<uint32_t>(out.data() + 12);
  const int64_t shift = static_cast<int64_t>(meta_text.size()) - static_cast<int64_t>(old_meta);
  const auto put64 = [&](size_t at, uint64_t v) { std::memcpy(out.data() + at, &v, 8); };
  const auto put32 = [&](size_t at, uint32_t v) { std::memcpy(out.data() + at, &v, 4); };
  put64(24, out.size());
  put64(32 + 16, meta_text.size());
  put32(32 + 24, Crc32c(std::span(reinterpret_cast<const uint8_t*>(meta_text.data()), meta_text.size())));
  for (uint32_t i = 1; i < sections; ++i) {
    put64(32 + 32 * i + 8, static_cast<uint64_t>(static_cast<int64_t>(LoadLE<uint64_t>(out.data() + 32 + 32 * i + 8)) + shift));
  }
  std::vector<uint8_t> head(out.begin(), out.begin() + 32 + 32 * sections);
  std::memset(head.data() + 16, 0, 4);
  put32(16, Crc32c(head));
  return out;
}

}  // namespace pointdag::testing
