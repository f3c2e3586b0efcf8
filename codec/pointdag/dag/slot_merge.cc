#include "pointdag/dag/slot_merge.h"

#include <algorithm>
#include <bit>
#include <optional>
#include <span>
#include <utility>

namespace pointdag {
namespace {

// An open-addressed table of ordinals (at most half full: sized by what is merged, never above the
// header's count) rather than a node-based map.
size_t TableBits(uint64_t declared, size_t items) {
  return static_cast<size_t>(std::bit_width(std::min<uint64_t>(declared, items))) + 1;
}

size_t Slot(uint64_t key, size_t bits) { return static_cast<size_t>(((key ^ (key >> 29)) * 0x9E3779B97F4A7C15ull) >> (64 - bits)); }

// A node's mask and children as one 64-bit key (equal nodes, equal keys).
uint64_t NodeKey(uint8_t mask, std::span<const uint32_t> kids) {
  uint64_t key = mask;
  for (uint32_t k : kids) key = (key ^ k) * 0x100000001B3ull;
  return key;
}

// Equal bricks become one: `ids` takes each slot's brick number.
// `declared`: the level table's count (none in version 8).
Status MergeBricks(const std::vector<uint64_t>& slots, std::optional<uint64_t> declared, std::vector<uint64_t>& leaves,
                   std::vector<uint32_t>& ids) {
  const size_t bits = TableBits(declared.value_or(slots.size()), slots.size());
  std::vector<uint32_t> table(size_t{1} << bits, UINT32_MAX);
  leaves.reserve(std::min<uint64_t>(declared.value_or(slots.size()), slots.size()));
  ids.reserve(slots.size());
  for (uint64_t brick : slots) {
    size_t at = Slot(brick, bits);
    while (table[at] != UINT32_MAX && leaves[table[at]] != brick) at = (at + 1) & (table.size() - 1);
    if (table[at] == UINT32_MAX) {
      if (leaves.size() == declared) return Corrupt("geometry stream holds more bricks than its header declares");
      table[at] = static_cast<uint32_t>(leaves.size());
      leaves.push_back(brick);
    }
    ids.push_back(table[at]);
  }
  if (declared && leaves.size() != *declared) return Corrupt("geometry stream holds fewer bricks than its header declares");
  return Status::Ok();
}

// Equal nodes of `level` (the same mask and children) become one; the level above then refers to
// their numbers.
Status MergeLevel(DagArrays& a, int level, std::optional<uint64_t> declared) {
  const std::vector<uint8_t>& masks = a.masks[level];
  const std::vector<uint32_t>& kids = a.children[level];
  const uint64_t most = std::min<uint64_t>(declared.value_or(masks.size()), masks.size());
  const size_t bits = TableBits(most, masks.size());
  std::vector<uint32_t> table(size_t{1} << bits, UINT32_MAX);
  std::vector<uint8_t> unique_masks;
  std::vector<uint32_t> unique_kids, starts;
  unique_masks.reserve(most);
  starts.reserve(most);
  std::vector<uint32_t> ids(masks.size());
  size_t pos = 0;
  for (size_t j = 0; j < masks.size(); ++j) {
    const std::span<const uint32_t> own(kids.data() + pos, std::popcount(static_cast<unsigned>(masks[j])));
    pos += own.size();
    size_t at = Slot(NodeKey(masks[j], own), bits);
    const auto same = [&](uint32_t u) {
      return unique_masks[u] == masks[j] && std::equal(own.begin(), own.end(), unique_kids.begin() + starts[u]);
    };
    while (table[at] != UINT32_MAX && !same(table[at])) at = (at + 1) & (table.size() - 1);
    if (table[at] == UINT32_MAX) {
      if (unique_masks.size() == declared) return Corrupt("geometry stream holds more nodes than its header declares");
      table[at] = static_cast<uint32_t>(unique_masks.size());
      unique_masks.push_back(masks[j]);
      starts.push_back(static_cast<uint32_t>(unique_kids.size()));
      unique_kids.insert(unique_kids.end(), own.begin(), own.end());
    }
    ids[j] = table[at];
  }
  if (declared && unique_masks.size() != *declared) return Corrupt("geometry stream holds fewer nodes than its header declares");
  a.masks[level] = std::move(unique_masks);
  a.children[level] = std::move(unique_kids);
  for (uint32_t& k : a.children[level - 1]) k = ids[k];
  return Status::Ok();
}

}  // namespace

bool SlotsStoredOnce(const DagArrays& arrays, int slot_level) {
  for (int level = slot_level; level < static_cast<int>(arrays.masks.size()); ++level) {
    const std::vector<uint8_t>& masks = arrays.masks[level];
    std::vector<size_t> starts(masks.size() + 1, 0);
    for (size_t k = 0; k < masks.size(); ++k) starts[k + 1] = starts[k] + std::popcount(static_cast<unsigned>(masks[k]));
    const auto kids = [&](size_t k) { return std::span<const uint32_t>(arrays.children[level]).subspan(starts[k], starts[k + 1] - starts[k]); };
    std::vector<std::pair<uint64_t, uint32_t>> keys(masks.size());
    for (size_t k = 0; k < masks.size(); ++k) keys[k] = {NodeKey(masks[k], kids(k)), static_cast<uint32_t>(k)};
    std::sort(keys.begin(), keys.end());
    for (size_t k = 0; k + 1 < keys.size(); ++k) {
      for (size_t j = k + 1; j < keys.size() && keys[j].first == keys[k].first; ++j) {
        const uint32_t a = keys[k].second, b = keys[j].second;
        if (masks[a] == masks[b] && std::equal(kids(a).begin(), kids(a).end(), kids(b).begin(), kids(b).end())) return false;
      }
    }
  }
  return true;
}

DagArrays ExpandSlots(const DagArrays& arrays, int slot_level) {
  DagArrays out = arrays;
  const int levels = static_cast<int>(arrays.masks.size());
  for (int level = slot_level; level < levels; ++level) {
    // Where each node's children start on the level as it was.
    const std::vector<uint8_t>& masks = arrays.masks[level];
    std::vector<size_t> starts(masks.size() + 1, 0);
    for (size_t k = 0; k < masks.size(); ++k) starts[k + 1] = starts[k] + std::popcount(static_cast<unsigned>(masks[k]));
    std::vector<uint8_t> copies;
    std::vector<uint32_t> kids;
    std::vector<uint32_t>& above = out.children[level - 1];
    for (uint32_t& k : above) {
      copies.push_back(masks[k]);
      kids.insert(kids.end(), arrays.children[level].begin() + starts[k], arrays.children[level].begin() + starts[k + 1]);
      k = static_cast<uint32_t>(copies.size() - 1);
    }
    out.masks[level] = std::move(copies);
    out.children[level] = std::move(kids);
  }
  return out;
}

Status MergeSlots(DagArrays& a, const std::vector<uint64_t>& slots, const std::vector<uint64_t>* counts, int slot_level) {
  const int levels = static_cast<int>(a.masks.size());
  const auto declared = [&](int level) { return counts ? std::optional<uint64_t>((*counts)[level]) : std::nullopt; };
  std::vector<uint32_t> ids;
  RETURN_IF_ERROR(MergeBricks(slots, declared(levels), a.leaves, ids));
  if (levels == 0) return Status::Ok();
  a.children.back() = std::move(ids);
  for (int level = levels - 1; level >= slot_level; --level) RETURN_IF_ERROR(MergeLevel(a, level, declared(level)));
  return Status::Ok();
}

}  // namespace pointdag
