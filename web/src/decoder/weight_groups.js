// Block color stream version 6's weights (codec/pointdag/color/prefix_weights.h and
// fixed_weight_codes.h; proto/PDAG_FORMAT.md §3): a block's b-bit weights in groups of 8 / b
// (b = 1, 2, 4) or 2 (b = 3) weights, the first in the lowest bits, each group one symbol of a
// canonical prefix code chosen by the width and the weight before the group (2^b: the block's first
// group). The codes are fixed: proto/tables/block_weight_codes_v6.txt (fixed_weight_codes.js is its copy).
import { corrupt } from './pdag_error.js';
import { FIXED_WEIGHT_CODES_TEXT } from './fixed_weight_codes.js';
import { buildPrefixTable } from './prefix_code.js';

export const weightsPerGroup = (bits) => (bits === 3 ? 2 : 8 / bits);
export const groupContexts = (bits) => (1 << bits) + 1;
export const groupSymbols = (bits) => (bits === 3 ? 64 : 256);

// Per width 1..4, its codes' lengths by context (Uint8Array(256) each), in the table's order.
export function fixedWeightCodeLengths(text = FIXED_WEIGHT_CODES_TEXT) {
  const lines = text.split('\n');
  if (lines.pop() !== '') throw new Error('the weight code table must end with a newline');
  const codes = [null];
  let line = 0;
  for (let bits = 1; bits <= 4; ++bits) {
    const byContext = [];
    for (let c = 0; c < groupContexts(bits); ++c, ++line) {
      const digits = lines[line] ?? '';
      if (digits.length !== groupSymbols(bits)) throw new Error(`weight code table line ${line + 1} has ${digits.length} lengths`);
      const lengths = new Uint8Array(256);
      for (let s = 0; s < digits.length; ++s) lengths[s] = parseInt(digits[s], 16);
      byContext.push(lengths);
    }
    codes.push(byContext);
  }
  if (line !== lines.length) throw new Error('the weight code table has lines past its 34 codes');
  return codes;
}

let tables = null;  // built on first use: [bits][context]
function fixedTables() {
  tables ??= fixedWeightCodeLengths().map((byContext) => byContext && byContext.map(buildPrefixTable));
  return tables;
}

// Reads the groups of a block's `length` weights of `bits` (1..4) from `groups` (a PrefixDecoder)
// into weights[0..length) as DecodeWeightGroups does; throws where a symbol is no code or sets a
// last group's unused bits.
export function readWeightGroups(groups, bits, length, weights) {
  const byContext = fixedTables()[bits];
  const groupBits = weightsPerGroup(bits) * bits;
  const m = (1 << bits) - 1;
  let context = 1 << bits;
  let i = 0;
  for (let left = length * bits; left > 0;) {
    const s = groups.get(byContext[context]);
    const take = Math.min(groupBits, left);
    if (s < 0 || s >>> take !== 0) throw corrupt('color weight group is no code, or sets bits past its block');
    for (let k = 0; k < take; k += bits) weights[i++] = (s >>> k) & m;
    left -= take;
    context = (s >>> (take - bits)) & m;
  }
}
