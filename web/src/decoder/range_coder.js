// The adaptive binary range decoder of codec/pointdag/entropy/binary_range_coder.h (LZMA-style,
// proto/PDAG_FORMAT.md §2.2) and the small codes over it (entropy/adaptive_codes.h), bit for bit.
//
// Models live in one Uint16Array per stream, two entries per model: the fast estimate (adapting by
// 1/16) at 2m and the slow one (1/128) at 2m+1, both P(bit = 0) in 1/65536; the coded probability
// is their mean in 12 bits. `range` and `code` are the C++ uint32 values held as int32 bit
// patterns: int32 arithmetic (Math.imul, | 0) wraps exactly as uint32 does, and unsigned comparisons
// flip the sign bit first. They live in an Int32Array, not in object fields: measured, a third
// faster than doubles or int32 fields in Chromium 156 and as fast as the best of those in Node 20.

const SIGN = 0x80000000;
const TOP_BYTE = 0xff000000;  // range < 2^24 <=> its top byte is zero

// Young models' rates in 1/65536 by age: 1/(n+2) until that is below 1/16 (fast) or 1/128 (slow).
const YOUNG = 127;
const YOUNG_FAST = Int32Array.from({ length: YOUNG + 1 }, (_, n) => Math.max(Math.floor(65536 / (n + 2)), 65536 >> 4));
const YOUNG_SLOW = Int32Array.from({ length: YOUNG + 1 }, (_, n) => Math.max(Math.floor(65536 / (n + 2)), 65536 >> 7));

export function newModels(count) {
  return new Uint16Array(2 * count).fill(32768);
}

// A young model's P(bit = 0) in 12 bits, and its update after `bit`, as youngBit does them.
export const youngP0 = (p, m) => ((p[2 * m] + p[2 * m + 1]) >>> 5) | 1;
export function youngUpdate(p, age, m, bit) {
  const target = bit ? 0 : 65535;
  const n = age[m];
  p[2 * m] += ((target - p[2 * m]) * YOUNG_FAST[n]) >> 16;
  p[2 * m + 1] += ((target - p[2 * m + 1]) * YOUNG_SLOW[n]) >> 16;
  if (n < YOUNG) age[m] = n + 1;
}

// Compact young models (CompactYoungModel): one estimate p (P(bit = 0) in 1/65536) and an age per
// model, moving by max(1/(n+2), 1/128).
const COMPACT_RATE = Int32Array.from({ length: YOUNG + 1 }, (_, n) => Math.max(Math.floor(65536 / (n + 2)), 65536 >> 7));
export const compactP0 = (p, m) => (p[m] >>> 4) | 1;
export function compactUpdate(p, age, m, bit) {
  const n = age[m];
  p[m] += (((bit ? 0 : 65535) - p[m]) * COMPACT_RATE[n]) >> 16;
  if (n < YOUNG) age[m] = n + 1;
}

// Bit tree of `bits` bits: models base+1 .. base+2^bits-1 (node 1, then node*2+bit).
export const bitTreeModels = (bits) => 1 << bits;

// Gamma code: 33 unary length models, then 33 bit trees of 3 bits (8 models each).
const GAMMA_MODELLED_BITS = 3;
export const GAMMA_MODELS = 33 + 33 * 8;

export class RangeDecoder {
  // Decodes bytes[start, end); past the end it reads zeros and counts them (overrun()). `compact`:
  // written by FinishCompact (geometry stream version 8), without the leading zero byte.
  constructor(bytes, start = 0, end = bytes.length, compact = false) {
    this.bytes = bytes;
    this.end = end;
    this.missing = 0;
    this.s = new Int32Array(3);  // range, code, position in bytes
    this.s[0] = -1;  // 0xffffffff
    this.s[2] = start;
    let code = 0;
    for (let i = compact ? 1 : 0; i < 5; ++i) code = (code << 8) | this.next();
    this.s[1] = code;
  }
  next() {
    const pos = this.s[2];
    if (pos < this.end) {
      this.s[2] = pos + 1;
      return this.bytes[pos];
    }
    ++this.missing;
    return 0;
  }
  // True once the decoder wanted more bytes than the input had: the stream was cut short.
  overrun() {
    return this.missing > 4;
  }
  bit(p, m) {
    const st = this.s;
    let range = st[0];
    let code = st[1];
    const f = p[2 * m];
    const s = p[2 * m + 1];
    const bound = Math.imul(range >>> 12, ((f + s) >>> 5) | 1);
    let bit;
    if ((code ^ SIGN) < (bound ^ SIGN)) {
      range = bound;
      p[2 * m] = f + ((65536 - f) >> 4);
      p[2 * m + 1] = s + ((65536 - s) >> 7);
      bit = 0;
    } else {
      code = (code - bound) | 0;
      range = (range - bound) | 0;
      p[2 * m] = f - (f >> 4);
      p[2 * m + 1] = s - (s >> 7);
      bit = 1;
    }
    this.settle(range, code);
    return bit;
  }
  // A bit of a model that learns fast while young (YoungBitModel in binary_range_coder.h): both
  // estimates move by max(1/(n+2), their own rate) after n updates; `age` holds n per model.
  youngBit(p, age, m) {
    const st = this.s;
    let range = st[0];
    let code = st[1];
    const f = p[2 * m];
    const s = p[2 * m + 1];
    const n = age[m];
    const bound = Math.imul(range >>> 12, ((f + s) >>> 5) | 1);
    let bit;
    let target;
    if ((code ^ SIGN) < (bound ^ SIGN)) {
      range = bound;
      bit = 0;
      target = 65535;
    } else {
      code = (code - bound) | 0;
      range = (range - bound) | 0;
      bit = 1;
      target = 0;
    }
    p[2 * m] = f + (((target - f) * YOUNG_FAST[n]) >> 16);
    p[2 * m + 1] = s + (((target - s) * YOUNG_SLOW[n]) >> 16);
    if (n < YOUNG) age[m] = n + 1;
    this.settle(range, code);
    return bit;
  }
  // A bit coded with P(bit = 0) = p0 / 4096 given outright (version 3's mixed mask bits).
  fixedBit(p0) {
    let range = this.s[0];
    let code = this.s[1];
    const bound = Math.imul(range >>> 12, p0);
    let bit = 0;
    if ((code ^ SIGN) < (bound ^ SIGN)) {
      range = bound;
    } else {
      code = (code - bound) | 0;
      range = (range - bound) | 0;
      bit = 1;
    }
    this.settle(range, code);
    return bit;
  }
  // Renormalises (a byte in while the range's top byte is zero) and keeps the state.
  settle(range, code) {
    while ((range & TOP_BYTE) === 0) {
      range <<= 8;
      code = (code << 8) | this.next();
    }
    this.s[0] = range;
    this.s[1] = code;
  }
  // Equiprobable bits, most significant first.
  direct(bits) {
    const st = this.s;
    let value = 0;
    for (let i = 0; i < bits; ++i) {
      let range = st[0] >>> 1;
      let code = st[1];
      let bit = 0;
      if ((code ^ SIGN) >= (range ^ SIGN)) {
        code = (code - range) | 0;
        bit = 1;
      }
      value = value * 2 + bit;
      this.settle(range, code);
    }
    return value;
  }
  bitTree(p, base, bits) {
    let node = 1;
    for (let i = 0; i < bits; ++i) node = (node << 1) | this.bit(p, base + node);
    return node - (1 << bits);
  }
  // A value >= 1: its bit length in unary (no terminator at maxLength), the top 3 bits below the
  // leading one through a bit tree per length, the rest equiprobable.
  gamma(p, base, maxLength) {
    let length = 1;
    while (length < maxLength && this.bit(p, base + length)) ++length;
    const modelled = length - 1 < GAMMA_MODELLED_BITS ? length - 1 : GAMMA_MODELLED_BITS;
    const rest = length - 1 - modelled;
    const top = (1 << modelled) | this.bitTree(p, base + 33 + 8 * length, modelled);
    return rest === 0 ? top : ((top << rest) | this.direct(rest)) >>> 0;
  }
}

// Bit length of v (0 for 0), as std::bit_width.
export const bitWidth = (v) => (v === 0 ? 0 : 32 - Math.clz32(v));

// Signed values of the gamma codes: 1, 2, 3, 4, ... -> 0, -1, 1, -2, ...
export const unZigZag = (z) => {
  const u = z - 1;
  return (u & 1) ? -((u + 1) / 2) : u / 2;
};
