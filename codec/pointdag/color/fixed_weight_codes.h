// Block color stream version 6's weight-group codes (prefix_weights.h; proto/PDAG_FORMAT.md §3): a
// canonical prefix code per width b and weight before the group (GroupContexts), their lengths fixed
// in the format instead of sent by every tile, so that a tile pays neither the lengths nor the
// tables' builds. The lengths are proto/tables/block_weight_codes_v6.txt (normative, its SHA-256 in
// the spec), compiled in as fixed_weight_codes.inc, which tools/weight_codes_trainer.cc writes from
// it; tests fail when the two differ.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "pointdag/entropy/prefix_code.h"

namespace pointdag {

struct FixedWeightCodes {
  // [bits][context], contexts 0..2^bits (GroupContexts); the others are empty.
  std::array<std::array<PrefixTable, 17>, 5> tables;
  std::array<std::vector<PrefixEncoder>, 5> encoders;
  std::array<std::array<std::array<uint8_t, 256>, 17>, 5> lengths{};  // b = 3: symbols 64.. are 0
};

// Built from the compiled-in text on first use, once per process.
const FixedWeightCodes& FixedWeightGroupCodes();

// The compiled-in copy of proto/tables/block_weight_codes_v6.txt, byte for byte.
std::string_view FixedWeightCodesText();

}  // namespace pointdag
