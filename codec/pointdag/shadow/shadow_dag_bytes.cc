// The shadow DAG's byte form, proto/SHADOW_FORMAT.md §1. Deserialize trusts nothing: sizes are
// checked against the buffer before anything is allocated (so memory is bounded by the input),
// every reference points strictly forward to a record start of the next level or into the leaves
// (so no cycle, no out-of-range read), and every record and leaf is reachable and canonical.
#include <cstring>

#include "pointdag/container/crc32c.h"
#include "pointdag/read/byte_io.h"
#include "pointdag/shadow/shadow_dag_impl.h"

namespace pointdag {
namespace {

constexpr size_t kHeaderBytes = 64;
constexpr size_t kCrcOffset = 60;
constexpr uint8_t kVersion = 1;
constexpr uint8_t kBelowHorizon = 1;

uint32_t FileCrc(std::span<const uint8_t> bytes) {
  return Crc32c(bytes.subspan(kHeaderBytes), Crc32c(bytes.first(kCrcOffset)));
}

// Checks the records and leaves of a kNode root (see shadow_dag_impl.h for their layout).
Status ValidateArrays(const std::vector<uint32_t>& nodes, const std::vector<uint64_t>& leaves, int light_depth) {
  if (nodes.empty()) return Malformed("shadow DAG: a node root without node words");
  const size_t words = nodes.size();
  std::vector<uint8_t> start(words, 0);
  for (size_t at = 0; at < words;) {
    const uint32_t header = nodes[at];
    const uint32_t pointers = header & 0xFFu, full = (header >> 8) & 0xFFu;
    if (header >> 16 != 0 || (pointers & full) != 0) return Malformed("shadow DAG: a node header with bad masks");
    if (pointers == 0 && (full == 0 || full == 0xFFu)) return Malformed("shadow DAG: an all-lit or all-shadowed node stored as a record");
    const size_t n = static_cast<size_t>(__builtin_popcount(pointers));
    if (n >= words - at) return Malformed("shadow DAG: a node record runs past the node words");
    start[at] = 1;
    at += 1 + n;
  }
  // Levels flow forward from the root: a record's parents all come before it.
  constexpr uint8_t kUnseen = 0xFF;
  std::vector<uint8_t> level(words, kUnseen);
  std::vector<uint8_t> leaf_used(leaves.size(), 0);
  level[0] = 0;
  const int last = light_depth - 3;
  for (size_t at = 0; at < words; at += 1 + static_cast<size_t>(__builtin_popcount(nodes[at] & 0xFFu))) {
    if (level[at] == kUnseen) return Malformed("shadow DAG: a node record nobody refers to");
    const int n = __builtin_popcount(nodes[at] & 0xFFu);
    for (int i = 1; i <= n; ++i) {
      const uint32_t child = nodes[at + i];
      if (level[at] == last) {
        if (child >= leaves.size()) return Malformed("shadow DAG: a leaf reference out of range");
        leaf_used[child] = 1;
        continue;
      }
      if (child <= at || child >= words || !start[child]) {
        return Malformed("shadow DAG: a node reference that is not a later record (out of range or a cycle)");
      }
      if (level[child] != kUnseen && level[child] != level[at] + 1) return Malformed("shadow DAG: a node on two levels");
      level[child] = static_cast<uint8_t>(level[at] + 1);
    }
  }
  for (size_t i = 0; i < leaves.size(); ++i) {
    if (!leaf_used[i]) return Malformed("shadow DAG: a leaf nobody refers to");
    if (leaves[i] == 0 || leaves[i] == ~uint64_t{0}) return Malformed("shadow DAG: an all-lit or all-shadowed leaf");
  }
  return Status::Ok();
}

}  // namespace

std::vector<uint8_t> ShadowDag::Serialize() const {
  const Impl& m = *impl_;
  std::vector<uint8_t> out;
  out.reserve(kHeaderBytes + m.nodes.size() * 4 + m.leaves.size() * 8);
  out.insert(out.end(), {'P', 'D', 'S', 'D', kVersion, static_cast<uint8_t>(m.below_horizon ? kBelowHorizon : 0),
                         static_cast<uint8_t>(m.frame.depth()), static_cast<uint8_t>(m.frame.light_depth())});
  for (double c : m.frame.travel()) AppendLE<double>(out, c);
  out.insert(out.end(), {static_cast<uint8_t>(m.root), 0, 0, 0});
  AppendLE<uint32_t>(out, static_cast<uint32_t>(m.nodes.size()));
  AppendLE<uint32_t>(out, static_cast<uint32_t>(m.leaves.size()));
  AppendLE<uint64_t>(out, m.stats.surface_voxels);
  AppendLE<uint64_t>(out, m.stats.shadowed_voxels);
  AppendLE<uint32_t>(out, 0);
  for (uint32_t w : m.nodes) AppendLE<uint32_t>(out, w);
  for (uint64_t leaf : m.leaves) AppendLE<uint64_t>(out, leaf);
  const uint32_t crc = FileCrc(out);
  std::memcpy(out.data() + kCrcOffset, &crc, 4);
  return out;
}

StatusOr<ShadowDag> ShadowDag::Deserialize(std::span<const uint8_t> bytes) {
  if (bytes.size() < kHeaderBytes) return Truncated("shadow DAG: shorter than its 64-byte header");
  const uint8_t* p = bytes.data();
  if (std::memcmp(p, "PDSD", 4) != 0) return Corrupt("shadow DAG: wrong magic (not PDSD)");
  if (p[4] != kVersion) return Unsupported("shadow DAG: unknown version " + std::to_string(p[4]));
  const uint64_t words = LoadLE<uint32_t>(p + 36), leaf_count = LoadLE<uint32_t>(p + 40);
  const uint64_t expected = kHeaderBytes + words * 4 + leaf_count * 8;
  if (bytes.size() < expected) return Truncated("shadow DAG: ends before its node words and leaves");
  if (bytes.size() > expected) return Malformed("shadow DAG: bytes after the leaves");
  if (LoadLE<uint32_t>(p + kCrcOffset) != FileCrc(bytes)) return Corrupt("shadow DAG: CRC-32C mismatch");
  if ((p[5] & ~kBelowHorizon) != 0 || p[33] != 0 || p[34] != 0 || p[35] != 0) return Malformed("shadow DAG: reserved bits set");

  auto impl = std::make_unique<Impl>();
  const std::array<double, 3> travel{LoadLE<double>(p + 8), LoadLE<double>(p + 16), LoadLE<double>(p + 24)};
  auto frame = LightFrame::Create(travel, p[6], p[7]);
  if (!frame.ok()) return Malformed("shadow DAG: " + frame.status().message());
  impl->frame = *frame;
  impl->below_horizon = (p[5] & kBelowHorizon) != 0;
  if (p[32] > static_cast<uint8_t>(ShadowRoot::kNode)) return Malformed("shadow DAG: unknown root kind");
  impl->root = static_cast<ShadowRoot>(p[32]);
  impl->stats.surface_voxels = LoadLE<uint64_t>(p + 44);
  impl->stats.shadowed_voxels = LoadLE<uint64_t>(p + 52);
  if (impl->stats.shadowed_voxels > impl->stats.surface_voxels) return Malformed("shadow DAG: more shadowed voxels than voxels");

  impl->nodes.resize(words);
  impl->leaves.resize(leaf_count);
  if (words != 0) std::memcpy(impl->nodes.data(), p + kHeaderBytes, words * 4);
  if (leaf_count != 0) std::memcpy(impl->leaves.data(), p + kHeaderBytes + words * 4, leaf_count * 8);
  if (impl->root != ShadowRoot::kNode) {
    if (words != 0 || leaf_count != 0) return Malformed("shadow DAG: an all-lit or all-shadowed root with nodes");
  } else {
    RETURN_IF_ERROR(ValidateArrays(impl->nodes, impl->leaves, impl->frame.light_depth()));
  }
  impl->FillSizeStats();
  return ShadowDag(std::move(impl));
}

}  // namespace pointdag
