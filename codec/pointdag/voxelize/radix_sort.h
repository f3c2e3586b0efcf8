// In-place MSD radix sort (American flag sort) of items by an unsigned key of at most key_bits bits.
//
// Contract: afterwards items are in ascending key order; the order among equal keys is unspecified
// (not stable). No scratch copy of the items: the voxelizer sorts every point of a scan at once and
// a copy would double its peak memory. Eight bits per pass from the top; runs shorter than 64
// items finish with std::sort.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace pointdag {

template <class T, class KeyFn>
void RadixSortInPlace(std::span<T> items, int key_bits, const KeyFn& key) {
  constexpr size_t kSmall = 64;
  if (items.size() < kSmall || key_bits <= 0) {
    std::sort(items.begin(), items.end(), [&](const T& a, const T& b) { return key(a) < key(b); });
    return;
  }
  const int shift = std::max(key_bits - 8, 0);
  const uint64_t mask = (uint64_t{1} << (key_bits - shift)) - 1;
  const auto digit = [&](const T& item) { return static_cast<size_t>((key(item) >> shift) & mask); };
  std::array<size_t, 256> counts{};
  for (const T& item : items) ++counts[digit(item)];
  std::array<size_t, 256> heads{}, ends{};
  size_t offset = 0;
  for (size_t d = 0; d < 256; ++d) {
    heads[d] = offset;
    offset += counts[d];
    ends[d] = offset;
  }
  // Each item is swapped straight into the next free slot of its bucket.
  for (size_t d = 0; d < 256; ++d) {
    while (heads[d] < ends[d]) {
      T item = items[heads[d]];
      for (size_t to = digit(item); to != d; to = digit(item)) std::swap(item, items[heads[to]++]);
      items[heads[d]++] = item;
    }
  }
  size_t begin = 0;
  for (size_t d = 0; d < 256; ++d) {
    if (counts[d] > 1) RadixSortInPlace(items.subspan(begin, counts[d]), shift, key);
    begin += counts[d];
  }
}

}  // namespace pointdag
