// Radix sort of items by an unsigned key of at most key_bits bits, with bounded scratch memory.
//
// Contract: afterwards items are in ascending key order; the order among equal keys is unspecified
// (not stable). The scratch memory is at most kRadixScratchItems items whatever the input's size:
// the voxelizer sorts every point of a scan at once and a full copy would double its peak memory.
// A run of more items is split in place (American flag sort, eight bits of the key from the top)
// until its parts fit; a part that fits is sorted least significant digit first through the
// scratch buffer (each pass moves an item once, where the in-place pass swaps it along a cycle);
// runs of at most kInsertionItems items are insertion sorted.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <utility>
#include <vector>

namespace pointdag {

// 1 MiB of 16-byte items: a few percent of a sort's time more than an unbounded buffer on 264k
// voxels (docs/benchmarks.md, goal 5's read and voxelize section), nothing beside a 10 M point scan.
inline constexpr size_t kRadixScratchItems = size_t{1} << 16;
inline constexpr size_t kInsertionItems = 24;

namespace radix_sort_internal {

template <class T, class KeyFn>
void InsertionSort(std::span<T> items, const KeyFn& key) {
  for (size_t i = 1; i < items.size(); ++i) {
    const T item = items[i];
    const uint64_t k = key(item);
    size_t j = i;
    for (; j > 0 && key(items[j - 1]) > k; --j) items[j] = items[j - 1];
    items[j] = item;
  }
}

// LSD passes over the bits in which the items' keys differ; scratch holds at least items.size().
template <class T, class KeyFn>
void SortThroughScratch(std::span<T> items, std::span<T> scratch, const KeyFn& key) {
  const size_t n = items.size();
  uint64_t differ = 0;
  const uint64_t first = key(items[0]);
  for (const T& item : items) differ |= key(item) ^ first;
  const int bits = static_cast<int>(std::bit_width(differ));
  if (bits == 0) return;
  // About n buckets a pass, at most 2^11 (the counts stay in the first-level cache).
  const int widest = std::clamp(static_cast<int>(std::bit_width(n)) - 1, 4, 11);
  const int passes = (bits + widest - 1) / widest;
  const int width = (bits + passes - 1) / passes;
  const uint64_t mask = (uint64_t{1} << width) - 1;
  std::array<uint32_t, size_t{1} << 11> counts;
  T* from = items.data();
  T* to = scratch.data();
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = pass * width;
    std::fill_n(counts.begin(), mask + 1, 0u);
    for (size_t i = 0; i < n; ++i) ++counts[(key(from[i]) >> shift) & mask];
    uint32_t offset = 0;
    for (size_t d = 0; d <= mask; ++d) offset += std::exchange(counts[d], offset);
    for (size_t i = 0; i < n; ++i) to[counts[(key(from[i]) >> shift) & mask]++] = from[i];
    std::swap(from, to);
  }
  if (from != items.data()) std::copy_n(from, n, items.data());
}

template <class T, class KeyFn>
void Sort(std::span<T> items, int key_bits, std::vector<T>& scratch, const KeyFn& key) {
  if (items.size() <= kInsertionItems || key_bits <= 0) {
    InsertionSort(items, key);
    return;
  }
  if (items.size() <= kRadixScratchItems) {
    if (scratch.size() < items.size()) scratch.resize(items.size());
    SortThroughScratch(items, std::span(scratch), key);
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
    if (counts[d] > 1) Sort(items.subspan(begin, counts[d]), shift, scratch, key);
    begin += counts[d];
  }
}

}  // namespace radix_sort_internal

template <class T, class KeyFn>
void RadixSortInPlace(std::span<T> items, int key_bits, const KeyFn& key) {
  std::vector<T> scratch;  // grown on first use, to at most kRadixScratchItems
  radix_sort_internal::Sort(items, key_bits, scratch, key);
}

}  // namespace pointdag
