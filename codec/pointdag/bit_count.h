// Set bits of a 64-bit word. std::popcount is a libgcc call on baseline x86-64 (no POPCNT, which
// the build does not require): the same count inline (a tile's decode spent 3 % in that call).
#pragma once

#include <array>
#include <bit>
#include <cstdint>

namespace pointdag {

// Set bits of a byte (a node mask): std::popcount of even 32 bits is that libgcc call too.
constexpr std::array<uint8_t, 256> kByteBits = [] {
  std::array<uint8_t, 256> t{};
  for (int i = 0; i < 256; ++i) t[i] = static_cast<uint8_t>(std::popcount(static_cast<unsigned>(i)));
  return t;
}();

inline uint32_t CountBits64(uint64_t v) {
#if defined(__POPCNT__) || !defined(__x86_64__)
  return static_cast<uint32_t>(std::popcount(v));
#else
  v -= (v >> 1) & 0x5555555555555555ull;
  v = (v & 0x3333333333333333ull) + ((v >> 2) & 0x3333333333333333ull);
  v = (v + (v >> 4)) & 0x0F0F0F0F0F0F0F0Full;
  return static_cast<uint32_t>((v * 0x0101010101010101ull) >> 56);
#endif
}

}  // namespace pointdag
