#include "pointdag/entropy/prefix_code.h"

#include <algorithm>
#include <numeric>
#include <queue>

namespace pointdag {
namespace {

// Huffman code lengths of the symbols with freq > 0 (at least two), unlimited.
std::array<uint8_t, 256> HuffmanLengths(const std::array<uint64_t, 256>& freq) {
  struct Node {
    uint64_t weight;
    int index;  // ties broken by index: deterministic
    bool operator>(const Node& o) const { return weight != o.weight ? weight > o.weight : index > o.index; }
  };
  std::vector<int> parent(512, -1);
  std::priority_queue<Node, std::vector<Node>, std::greater<>> queue;
  for (int s = 0; s < 256; ++s) {
    if (freq[s] > 0) queue.push({freq[s], s});
  }
  int next = 256;
  while (queue.size() > 1) {
    const Node a = queue.top();
    queue.pop();
    const Node b = queue.top();
    queue.pop();
    parent[a.index] = parent[b.index] = next;
    queue.push({a.weight + b.weight, next++});
  }
  std::array<uint8_t, 256> lengths{};
  for (int s = 0; s < 256; ++s) {
    if (freq[s] == 0) continue;
    int depth = 0;
    for (int n = s; parent[n] >= 0; n = parent[n]) ++depth;
    lengths[s] = static_cast<uint8_t>(std::min(depth, 255));
  }
  return lengths;
}

}  // namespace

std::array<uint8_t, 256> PrefixCodeLengths(const std::array<uint64_t, 256>& freq) {
  const int used = static_cast<int>(std::count_if(freq.begin(), freq.end(), [](uint64_t f) { return f > 0; }));
  std::array<uint8_t, 256> lengths{};
  if (used == 1) {
    for (int s = 0; s < 256; ++s) lengths[s] = freq[s] > 0 ? 1 : 0;
    return lengths;
  }
  if (used == 0) return lengths;
  std::array<uint64_t, 256> f = freq;
  for (;;) {
    lengths = HuffmanLengths(f);
    if (*std::max_element(lengths.begin(), lengths.end()) <= kPrefixCodeBits) return lengths;
    for (uint64_t& x : f) x = x > 0 ? (x + 1) / 2 : 0;  // flatter: shorter longest code
  }
}

void BitWriter::Put(uint32_t code, int length) {
  acc_ = acc_ << length | code;
  bits_ += length;
  while (bits_ >= 8) {
    bits_ -= 8;
    bytes_.push_back(static_cast<uint8_t>(acc_ >> bits_));
  }
}

std::vector<uint8_t> BitWriter::Finish() {
  if (bits_ > 0) bytes_.push_back(static_cast<uint8_t>(acc_ << (8 - bits_)));
  bits_ = 0;
  return std::move(bytes_);
}

namespace {

// How many symbols take each length; lengths above kPrefixCodeBits all count as kPrefixCodeBits + 1.
using LengthCounts = std::array<uint32_t, kPrefixCodeBits + 2>;

LengthCounts CountLengths(const std::array<uint8_t, 256>& lengths) {
  LengthCounts count{};
  for (uint8_t len : lengths) ++count[std::min<int>(len, kPrefixCodeBits + 1)];
  return count;
}

// Canonical codes: by length, then symbol; each the previous plus one, shifted left as lengths grow.
// The first code of each length from a count of the lengths, then the symbols in one pass (DEFLATE's
// way; a pass over the symbols per length was most of a small tile's table building).
template <typename Visit>
void CanonicalCodes(const std::array<uint8_t, 256>& lengths, const LengthCounts& count, Visit visit) {
  std::array<uint32_t, kPrefixCodeBits + 1> next{};
  for (int len = 2; len <= kPrefixCodeBits; ++len) next[len] = (next[len - 1] + count[len - 1]) << 1;
  for (int s = 0; s < 256; ++s) {
    if (lengths[s] > 0) visit(s, lengths[s], next[lengths[s]]++);
  }
}

}  // namespace

PrefixEncoder::PrefixEncoder(const std::array<uint8_t, 256>& lengths) : lengths_(lengths) {
  CanonicalCodes(lengths, CountLengths(lengths), [&](int s, int, uint32_t code) { code_[s] = static_cast<uint16_t>(code); });
}

Status BuildPrefixTable(const std::array<uint8_t, 256>& lengths, PrefixTable& table) {
  // One pass over the symbols counts the lengths; the checks, the longest and the Kraft sum come
  // from the counts (three passes over the symbols were half of building a small tile's tables).
  const LengthCounts count = CountLengths(lengths);
  if (count[kPrefixCodeBits + 1] > 0) {
    const uint8_t len = *std::max_element(lengths.begin(), lengths.end());
    return Corrupt("prefix code length " + std::to_string(len) + " exceeds 12");
  }
  uint32_t kraft = 0;  // in 2^-kPrefixCodeBits
  table.bits = 0;
  for (int len = 1; len <= kPrefixCodeBits; ++len) {
    kraft += count[len] << (kPrefixCodeBits - len);
    if (count[len] > 0) table.bits = len;
  }
  if (kraft > (1u << kPrefixCodeBits)) return Corrupt("prefix code lengths over-subscribe the code space");
  table.entries.assign(size_t{1} << table.bits, 0);
  CanonicalCodes(lengths, count, [&](int s, int len, uint32_t code) {
    const uint32_t first = code << (table.bits - len);
    std::fill_n(table.entries.begin() + first, size_t{1} << (table.bits - len), static_cast<uint16_t>(len << 8 | s));
  });
  return Status::Ok();
}

}  // namespace pointdag
