// LEB128 variable-length unsigned integers: 7 bits a byte, low bits first.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace pointdag {

inline void PutVarint(std::vector<uint8_t>& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<uint8_t>(v));
}

// Reads one varint at `pos` and advances it; false when the input ends first or it overflows 64 bits.
inline bool GetVarint(std::span<const uint8_t> in, size_t& pos, uint64_t& v) {
  v = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    if (pos >= in.size()) return false;
    const uint8_t b = in[pos++];
    v |= uint64_t{b & 0x7Fu} << shift;
    if (!(b & 0x80)) return true;
  }
  return false;
}

}  // namespace pointdag
