#include "pointdag/entropy/code_lengths.h"

#include <algorithm>
#include <cstdlib>
#include <string>

namespace pointdag {
namespace {

// Whether sending the lengths beats 8 bits a symbol, by an estimate of the lengths' cost.
bool WorthATable(const std::array<uint64_t, 256>& freq, const std::array<uint8_t, 256>& lengths, int first) {
  uint64_t plain = 0, coded = 0, used = 0;
  for (int s = first; s < 256; ++s) {
    plain += 8 * freq[s];
    coded += freq[s] * lengths[s];
    used += lengths[s] > 0 ? 1 : 0;
  }
  return coded + 5 * used + 255 / 2 < plain;
}

}  // namespace

std::array<uint8_t, 256> WriteCodeLengths(BinaryRangeEncoder& rc, CodeLengthModels& m, const std::array<uint64_t, 256>& freq,
                                          int first) {
  const std::array<uint8_t, 256> lengths = PrefixCodeLengths(freq);
  const bool coded = WorthATable(freq, lengths, first);
  rc.Encode(m.coded, coded ? 1 : 0);
  if (coded) {
    int previous = 0;
    for (int s = first; s < 256; ++s) {
      EncodeBitTree<4>(rc, m.length[previous], lengths[s]);
      previous = lengths[s];
    }
    return lengths;
  }
  std::array<uint8_t, 256> plain{};
  for (int s = first; s < 256; ++s) plain[s] = 8;
  return plain;
}

StatusOr<bool> ReadCodeLengths(BinaryRangeDecoder& rc, CodeLengthModels& m, int first, std::array<uint8_t, 256>& lengths) {
  std::fill_n(lengths.begin(), first, 0);
  if (rc.Decode(m.coded) == 0) {
    std::fill(lengths.begin() + first, lengths.end(), 8);
    return false;
  }
  // A copy in registers: the lengths are bytes, whose stores could alias the caller's decoder and
  // would send its state through memory after every symbol. One check of them all at the end; a
  // length above 12 reads on in tree 12 and refuses the stream.
  BinaryRangeDecoder local = rc;
  uint32_t previous = 0, longest = 0;
  for (int s = first; s < 256; ++s) {
    const uint32_t length = DecodeBitTree<4>(local, m.length[previous]);
    lengths[s] = static_cast<uint8_t>(length);
    longest = std::max(longest, length);
    previous = std::min<uint32_t>(length, kPrefixCodeBits);
  }
  rc = local;
  if (longest > kPrefixCodeBits) return Corrupt("a prefix code length above " + std::to_string(kPrefixCodeBits));
  return true;
}

const PrefixTable& PlainPrefixTable(int first) {
  static const std::array<PrefixTable, 2> tables = [] {
    std::array<PrefixTable, 2> t;
    for (int f = 0; f < 2; ++f) {
      std::array<uint8_t, 256> lengths{};
      std::fill(lengths.begin() + f, lengths.end(), 8);
      if (!BuildPrefixTable(lengths, t[f]).ok()) std::abort();  // a complete code of 8-bit lengths
    }
    return t;
  }();
  return tables[first > 0 ? 1 : 0];
}

}  // namespace pointdag
