// Canonical prefix codes over bytes (codec/pointdag/entropy/prefix_code.h), read by table lookup,
// bit for bit as the C++ decoder reads them: most significant bit first, zeros past the end.
import { corrupt } from './pdag_error.js';

export const PREFIX_CODE_BITS = 12;
const PEEK_MASK = (1 << PREFIX_CODE_BITS) - 1;

// The canonical code of `lengths` (256 entries, 0 = absent) as a lookup table of `bits`-bit
// patterns, `bits` the longest code: entry = symbol | length << 8, 0 where no code starts. Sized by
// the longest code, so that a small tile's short codes fill a few hundred entries, not 4096.
export function buildPrefixTable(lengths) {
  let kraft = 0;
  let bits = 0;
  for (let s = 0; s < 256; ++s) {
    if (lengths[s] > PREFIX_CODE_BITS) throw corrupt(`prefix code length ${lengths[s]} exceeds 12`);
    if (lengths[s] > 0) kraft += 1 << (PREFIX_CODE_BITS - lengths[s]);
    bits = Math.max(bits, lengths[s]);
  }
  if (kraft > 1 << PREFIX_CODE_BITS) throw corrupt('prefix code lengths over-subscribe the code space');
  const entries = new Uint16Array(1 << bits);
  let code = 0;
  for (let len = 1; len <= bits; ++len) {
    for (let s = 0; s < 256; ++s) {
      if (lengths[s] !== len) continue;
      const first = code << (bits - len);
      entries.fill((len << 8) | s, first, first + (1 << (bits - len)));
      ++code;
    }
    code <<= 1;
  }
  return { bits, entries };
}

export class PrefixDecoder {
  // Reads bytes[start, end).
  constructor(bytes, start, end) {
    this.bytes = bytes;
    this.start = start;
    this.end = end;
    this.pos = 0;  // bits read
  }
  // The next symbol, or -1 at a bit pattern that is no code.
  get(table) {
    const e = table.entries[this.peek() >>> (PREFIX_CODE_BITS - table.bits)];
    this.pos += e >>> 8;
    return e >>> 8 ? e & 0xff : -1;
  }
  // `n` (0..31) raw bits, most significant first (PrefixDecoder::Bits).
  bits(n) {
    let v = 0;
    while (n > 0) {
      const take = Math.min(n, PREFIX_CODE_BITS);
      v = (v * (1 << take)) + (this.peek() >>> (PREFIX_CODE_BITS - take));
      this.pos += take;
      n -= take;
    }
    return v;
  }
  // The next 12 bits, zeros past the end.
  peek() {
    const { bytes, end } = this;
    const at = this.start + (this.pos >>> 3);
    const v = at + 3 <= end
      ? (bytes[at] << 16) | (bytes[at + 1] << 8) | bytes[at + 2]
      : ((at < end ? bytes[at] : 0) << 16) | ((at + 1 < end ? bytes[at + 1] : 0) << 8) | (at + 2 < end ? bytes[at + 2] : 0);
    return (v >>> (12 - (this.pos & 7))) & PEEK_MASK;
  }
  overrun() {
    return this.pos > 8 * (this.end - this.start);
  }
}
