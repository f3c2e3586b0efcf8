#include "pointdag/entropy/code_lengths.h"

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

Status ReadCodeLengths(BinaryRangeDecoder& rc, CodeLengthModels& m, int first, std::array<uint8_t, 256>& lengths) {
  lengths.fill(0);
  const bool coded = rc.Decode(m.coded) != 0;
  int previous = 0;
  for (int s = first; s < 256; ++s) {
    lengths[s] = static_cast<uint8_t>(coded ? DecodeBitTree<4>(rc, m.length[previous]) : 8);
    if (lengths[s] > kPrefixCodeBits) return Corrupt("a prefix code length above " + std::to_string(kPrefixCodeBits));
    previous = lengths[s];
  }
  return Status::Ok();
}

}  // namespace pointdag
