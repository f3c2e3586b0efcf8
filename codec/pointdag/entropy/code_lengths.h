// The code lengths of a canonical prefix code (prefix_code.h) sent in a range-coded section, for
// the streams whose symbols are read by table lookup (geometry coder 3's masks, block color stream
// version 5's weight groups; proto/PDAG_FORMAT.md §2.2 and §3): a flag, then, where a code pays for
// its lengths, the length of every symbol from `first` to 255 as a 4-bit tree chosen by the previous
// symbol's length; where it does not, every symbol takes 8 bits.
#pragma once

#include <array>
#include <cstdint>

#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/entropy/prefix_code.h"
#include "pointdag/status.h"

namespace pointdag {

struct CodeLengthModels {
  BitModel coded;                                           // 1: the lengths follow, 0: 8 bits a symbol
  std::array<BitTreeModel<4>, kPrefixCodeBits + 1> length;  // by the previous symbol's length
};

// The Huffman code of `freq` (symbols `first`..255) or 8 bits a symbol, whichever an estimate of the
// lengths' own cost finds smaller; writes the choice and returns the lengths the stream now uses.
std::array<uint8_t, 256> WriteCodeLengths(BinaryRangeEncoder& rc, CodeLengthModels& m, const std::array<uint64_t, 256>& freq,
                                          int first);

// Reads what WriteCodeLengths wrote (symbols below `first` get length 0): true when the lengths were
// sent, false for 8 bits a symbol (whose table PlainPrefixTable holds); kCorrupt for a length above
// kPrefixCodeBits.
StatusOr<bool> ReadCodeLengths(BinaryRangeDecoder& rc, CodeLengthModels& m, int first, std::array<uint8_t, 256>& lengths);

// The table of 8 bits a symbol for symbols `first` (0 or 1) to 255, built once per process: most
// classes of a small tile's masks send no lengths, and each would otherwise build this table again.
const PrefixTable& PlainPrefixTable(int first);

}  // namespace pointdag
