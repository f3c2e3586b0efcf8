#include "pointdag/container/crc32c.h"

#include <array>
#include <cstring>

#if defined(__x86_64__) && !defined(__EMSCRIPTEN__)
#include <nmmintrin.h>
#define POINTDAG_CRC32C_SSE42 1
#endif

namespace pointdag {
namespace {

// Slice-by-4 tables: four bytes per step keeps checksumming off the profile of decode.
constexpr std::array<std::array<uint32_t, 256>, 4> MakeTables() {
  std::array<std::array<uint32_t, 256>, 4> t{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0x82F63B78u & (0u - (c & 1u)));
    t[0][i] = c;
  }
  for (uint32_t i = 0; i < 256; ++i) {
    for (int s = 1; s < 4; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFFu];
  }
  return t;
}

constexpr auto kTables = MakeTables();

#ifdef POINTDAG_CRC32C_SSE42
// SSE 4.2's crc32 instruction computes exactly this polynomial (Castagnoli, reflected), 8 bytes an
// instruction: a tile's sections are checksummed in a tenth of the table's instructions.
__attribute__((target("sse4.2"))) uint32_t Crc32cSse42(std::span<const uint8_t> data, uint32_t crc) {
  uint64_t c = ~crc;
  size_t i = 0;
  for (; i + 8 <= data.size(); i += 8) {
    uint64_t word;
    std::memcpy(&word, data.data() + i, 8);
    c = _mm_crc32_u64(c, word);
  }
  uint32_t c32 = static_cast<uint32_t>(c);
  for (; i < data.size(); ++i) c32 = _mm_crc32_u8(c32, data[i]);
  return ~c32;
}

const bool kHaveSse42 = __builtin_cpu_supports("sse4.2");
#endif

}  // namespace

uint32_t Crc32c(std::span<const uint8_t> data, uint32_t crc) {
#ifdef POINTDAG_CRC32C_SSE42
  if (kHaveSse42) return Crc32cSse42(data, crc);
#endif
  crc = ~crc;
  size_t i = 0;
  for (; i + 4 <= data.size(); i += 4) {
    crc ^= uint32_t{data[i]} | uint32_t{data[i + 1]} << 8 | uint32_t{data[i + 2]} << 16 | uint32_t{data[i + 3]} << 24;
    crc = kTables[3][crc & 0xFFu] ^ kTables[2][(crc >> 8) & 0xFFu] ^ kTables[1][(crc >> 16) & 0xFFu] ^
          kTables[0][crc >> 24];
  }
  for (; i < data.size(); ++i) crc = (crc >> 8) ^ kTables[0][(crc ^ data[i]) & 0xFFu];
  return ~crc;
}

}  // namespace pointdag
