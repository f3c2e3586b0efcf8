// Block color stream version 6's weights (proto/PDAG_FORMAT.md §3): a block's weights of b bits go
// in groups of 8 / b (b = 1, 2, 4) or 2 (b = 3) weights, the first in the lowest bits, a group one
// symbol of a canonical prefix code (prefix_code.h) chosen by the width and the weight before the
// group, so that a decoder reads 2..8 weights with one table lookup instead of b adaptive binary
// decisions each. A block's last group holds what is left, its unused high bits 0. A group's bits
// are the weights exactly as BlockColorDecoder packs them, so they are copied as they come.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/entropy/prefix_code.h"

namespace pointdag {

constexpr int WeightsPerGroup(int bits) { return bits == 3 ? 2 : 8 / bits; }
// A group's code: by the weight before it in the block (2^bits: the block's first group).
constexpr int GroupContexts(int bits) { return (1 << bits) + 1; }
// Symbols of a group of width `bits`: 64 for b = 3 (two weights), else 256.
constexpr int GroupSymbols(int bits) { return bits == 3 ? 64 : 256; }

// The group symbols of one block's weights of `bits` (1..4), appended in order.
void AppendWeightGroups(std::span<const uint8_t> weights, int bits, std::vector<uint8_t>& symbols);

// Reads the groups of `length` weights of `bits` (1..4) with `tables` (GroupContexts(bits) of them,
// by context) and packs the weights from bit `bit_offset` of `words` (sized by the caller, the bits
// past `bit_offset` zero). False at a symbol that is no code or sets a last group's unused bits.
bool DecodeWeightGroups(PrefixDecoder& in, const PrefixTable* tables, int bits, uint32_t length, uint64_t* words,
                        uint64_t bit_offset);

}  // namespace pointdag
