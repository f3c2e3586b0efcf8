#include "pointdag/color/prefix_weights.h"

#include <algorithm>

namespace pointdag {

void AppendWeightGroups(std::span<const uint8_t> weights, int bits, std::vector<uint8_t>& symbols) {
  const size_t per_group = static_cast<size_t>(WeightsPerGroup(bits));
  for (size_t i = 0; i < weights.size(); i += per_group) {
    uint32_t symbol = 0;
    for (size_t k = 0; k < per_group && i + k < weights.size(); ++k) symbol |= uint32_t{weights[i + k]} << (k * static_cast<size_t>(bits));
    symbols.push_back(static_cast<uint8_t>(symbol));
  }
}

bool DecodeWeightGroups(PrefixDecoder& in, const PrefixTable* tables, int bits, uint32_t length, uint64_t* words,
                        uint64_t bit_offset) {
  const unsigned group_bits = static_cast<unsigned>(WeightsPerGroup(bits) * bits);
  // The word being filled stays in a register: one store per 64 bits.
  uint64_t* word = words + (bit_offset >> 6);
  unsigned used = bit_offset & 63;
  uint64_t pending = *word;  // the bits below `used` are earlier blocks'
  unsigned context = 1u << bits;
  for (uint64_t left = uint64_t{length} * static_cast<uint64_t>(bits); left > 0;) {
    const int s = in.Get(tables[context]);
    const unsigned take = static_cast<unsigned>(std::min<uint64_t>(group_bits, left));
    if (s < 0 || (static_cast<uint32_t>(s) >> take) != 0) return false;
    pending |= uint64_t(static_cast<uint32_t>(s)) << used;
    used += take;
    if (used >= 64) {
      *word++ = pending;
      used -= 64;
      pending = used ? uint64_t(static_cast<uint32_t>(s)) >> (take - used) : 0;
    }
    left -= take;
    context = (static_cast<uint32_t>(s) >> (take - static_cast<unsigned>(bits))) & ((1u << bits) - 1);
  }
  *word = pending;
  return true;
}

}  // namespace pointdag
