#include "pointdag/color/fixed_weight_codes.h"

#include <cstdlib>

#include "pointdag/color/prefix_weights.h"

namespace pointdag {
namespace {

// kFixedWeightCodesText: the table's text, 34 lines (widths 1..4, contexts 0..2^b), a hex digit per
// symbol's code length.
#include "pointdag/color/fixed_weight_codes.inc"

int HexDigit(char c) { return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1; }

}  // namespace

std::string_view FixedWeightCodesText() { return {kFixedWeightCodesText, sizeof(kFixedWeightCodesText) - 1}; }

const FixedWeightCodes& FixedWeightGroupCodes() {
  static const FixedWeightCodes codes = [] {
    FixedWeightCodes c;
    std::string_view text = FixedWeightCodesText();
    for (int bits = 1; bits <= 4; ++bits) {
      for (int ctx = 0; ctx < GroupContexts(bits); ++ctx) {
        const size_t n = static_cast<size_t>(GroupSymbols(bits));
        // The text is compiled in: a malformed copy is a build error, which every test shows.
        if (text.size() < n + 1 || text[n] != '\n') std::abort();
        std::array<uint8_t, 256>& lengths = c.lengths[bits][ctx];
        for (size_t s = 0; s < n; ++s) {
          const int length = HexDigit(text[s]);
          if (length < 1 || length > kPrefixCodeBits) std::abort();
          lengths[s] = static_cast<uint8_t>(length);
        }
        text.remove_prefix(n + 1);
        if (!BuildPrefixTable(lengths, c.tables[bits][ctx]).ok()) std::abort();
        c.encoders[bits].emplace_back(lengths);
      }
    }
    if (!text.empty()) std::abort();
    return c;
  }();
  return codes;
}

}  // namespace pointdag
