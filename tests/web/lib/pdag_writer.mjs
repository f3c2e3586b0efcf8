// Writers for hostile test input: the .pdag container with valid CRCs around any sections, and a
// context-coded geometry stream for any (possibly lying) DAG. A port of the C++ encoder side
// (entropy/binary_range_coder.h BinaryRangeEncoder, dag/dag_stream.cc WriteSymbols), for tests only.
import { crc32c } from '../../../web/src/decoder/crc32c.js';
import { GAMMA_MODELS, bitWidth, newModels } from '../../../web/src/decoder/range_coder.js';

const MAGIC = [0x50, 0x44, 0x41, 0x47, 0x0d, 0x0a, 0x1a, 0x0a];

// sections: [[tag, Uint8Array], ...] in order; `major` to forge another version.
export function framePdag(sections, { major = 1 } = {}) {
  const tableEnd = 32 + 32 * sections.length;
  const total = tableEnd + sections.reduce((n, [, d]) => n + d.length, 0);
  const out = new Uint8Array(total);
  const v = new DataView(out.buffer);
  out.set(MAGIC, 0);
  v.setUint16(8, major, true);
  v.setUint32(12, sections.length, true);
  v.setUint32(24, total, true);
  let offset = tableEnd;
  sections.forEach(([tag, data], i) => {
    const e = 32 + 32 * i;
    for (let k = 0; k < Math.min(8, tag.length); ++k) out[e + k] = tag.charCodeAt(k);
    v.setUint32(e + 8, offset, true);
    v.setUint32(e + 16, data.length, true);
    v.setUint32(e + 24, crc32c(data), true);
    out.set(data, offset);
    offset += data.length;
  });
  v.setUint32(16, crc32c(out.subarray(0, tableEnd)), true);  // the CRC field is still zero here
  return out;
}

export const utf8 = (text) => new TextEncoder().encode(text);

// The sections of a real .pdag, as views: [[tag, Uint8Array], ...].
export function sectionsOf(bytes) {
  const v = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const sections = [];
  for (let i = 0; i < v.getUint32(12, true); ++i) {
    const e = 32 + 32 * i;
    let tag = '';
    for (let k = 0; k < 8 && bytes[e + k]; ++k) tag += String.fromCharCode(bytes[e + k]);
    const offset = v.getUint32(e + 8, true);
    sections.push([tag, bytes.subarray(offset, offset + v.getUint32(e + 16, true))]);
  }
  return sections;
}

export function varint(v) {
  const out = [];
  for (; v >= 0x80; v = Math.floor(v / 128)) out.push((v % 128) | 0x80);
  out.push(v);
  return out;
}

class RangeEncoder {
  constructor() {
    this.low = 0;  // up to 2^32 + 2^32: exact in a double
    this.range = 0xffffffff;
    this.cache = 0;
    this.cacheSize = 1;
    this.out = [];
  }
  bit(p, m, bit) {
    const f = p[2 * m], s = p[2 * m + 1];
    const bound = (this.range >>> 12) * (((f + s) >>> 5) | 1);
    if (bit === 0) {
      this.range = bound;
      p[2 * m] = f + ((65536 - f) >> 4);
      p[2 * m + 1] = s + ((65536 - s) >> 7);
    } else {
      this.low += bound;
      this.range -= bound;
      p[2 * m] = f - (f >> 4);
      p[2 * m + 1] = s - (s >> 7);
    }
    this.normalize();
  }
  direct(value, bits) {
    for (let i = bits - 1; i >= 0; --i) {
      this.range = this.range >>> 1;
      if (Math.floor(value / 2 ** i) % 2) this.low += this.range;
      this.normalize();
    }
  }
  bitTree(p, base, value, bits) {
    let node = 1;
    for (let i = bits - 1; i >= 0; --i) {
      const b = (value >> i) & 1;
      this.bit(p, base + node, b);
      node = (node << 1) | b;
    }
  }
  gamma(p, base, v, maxLength) {
    const length = bitWidth(v);
    for (let i = 1; i < length; ++i) this.bit(p, base + i, 1);
    if (length < maxLength) this.bit(p, base + length, 0);
    const modelled = Math.min(length - 1, 3);
    const rest = length - 1 - modelled;
    this.bitTree(p, base + 33 + 8 * length, (v >>> rest) & ((1 << modelled) - 1), modelled);
    this.direct(v & ((1 << rest) - 1), rest);
  }
  normalize() {
    while (this.range < 2 ** 24) {
      this.range *= 256;
      this.shiftLow();
    }
  }
  shiftLow() {
    if (this.low < 0xff000000 || this.low >= 2 ** 32) {
      const carry = this.low >= 2 ** 32 ? 1 : 0;
      let pending = this.cache;
      do {
        this.out.push((pending + carry) & 0xff);
        pending = 0xff;
      } while (--this.cacheSize !== 0);
      this.cache = Math.floor(this.low / 2 ** 24) & 0xff;
    }
    ++this.cacheSize;
    this.low = (this.low % 2 ** 24) * 256;
  }
  finish() {
    for (let i = 0; i < 5; ++i) this.shiftLow();
    return this.out;
  }
}

// A context-coded geometry stream. `levels`: per internal level, its nodes as {mask, kids}, kids
// being child ordinals on the next level in octant order; `bricks`: [lo, hi] masks. `table`
// overrides the level table (to lie about the counts).
export function writeGeometry({ depth, mode, levels, bricks, table }) {
  const counts = table ?? [...levels.map((l) => l.length), bricks.length];
  const rc = new RangeEncoder();
  const p = newModels(22 * 256 + 22 + 22 * GAMMA_MODELS);
  const flag = (cls) => 22 * 256 + cls;
  const ref = (cls) => 22 * 256 + 22 + cls * GAMMA_MODELS;
  levels.forEach((nodes, level) => {
    const cls = depth - level;
    let seen = 0;
    for (const { mask, kids } of nodes) {
      rc.bitTree(p, cls * 256, mask, 8);
      for (const k of kids) {
        if (seen > 0) rc.bit(p, flag(cls), k < seen ? 1 : 0);
        if (k < seen) rc.gamma(p, ref(cls), k + 1, bitWidth(seen));
        else ++seen;
      }
    }
  });
  for (const [lo, hi] of bricks) {
    let cells = 0;
    for (let c = 0; c < 8; ++c) if (((c < 4 ? lo : hi) >>> (8 * (c % 4))) & 0xff) cells |= 1 << c;
    rc.bitTree(p, 2 * 256, cells, 8);
    for (let c = 0; c < 8; ++c) if ((cells >> c) & 1) rc.bitTree(p, 256, ((c < 4 ? lo : hi) >>> (8 * (c % 4))) & 0xff, 8);
  }
  return new Uint8Array([1, 1, depth, mode, ...counts.flatMap(varint), ...rc.finish()]);
}

// The solid cube of side 2^depth as a DAG of one node per level (8^depth voxels in a few bytes).
export function denseCube(depth, mode) {
  const levels = [];
  for (let level = 0; level < depth - 2; ++level) levels.push([{ mask: 0xff, kids: [0, 0, 0, 0, 0, 0, 0, 0] }]);
  return { depth, mode, levels, bricks: [[0xffffffff, 0xffffffff]] };
}
