// The stored SVDAG (proto/PDAG_FORMAT.md §2.2), read as codec/pointdag/dag/dag_stream.cc DecodeDag
// reads it, with the same checks in the same order, into flat typed arrays:
//   masks[L]      Uint8Array, the child mask of each node of internal level L (canonical order)
//   firstChild[L] Uint32Array(n+1), where node i's children start in children[L]
//   children[L]   Uint32Array, child ordinals on level L+1 (brick indices below the last level)
//   brickLo/Hi    Uint32Array, the 64-bit brick masks (cells 0-3 in Lo, 4-7 in Hi)
// plus each node's count (§2.3: voxels in leaf mode, nodes and voxels in mipmap mode) and its
// voxel count, bottom-up, as doubles (exact far beyond any limit they are compared with).
import { corrupt, resourceLimit, unsupported } from './pdag_error.js';
import { GrowableU32 } from './growable_u32.js';
import { GAMMA_MODELS, RangeDecoder, bitTreeModels, bitWidth, newModels } from './range_coder.js';
import { PREFIX_CODE_BITS, PrefixDecoder, buildPrefixTable } from './prefix_code.js';
import { COMPACT_SPATIAL_VERSION, decodeCompactSpatial, decodeSpatial } from './spatial_coder.js';
import { readVarint } from './varint.js';

export const MAX_DEPTH = 21;
export const COUNT_LEAVES = 0;
export const COUNT_MIPMAP = 1;

// Versions 2..5 and 8 change coder 2 only; versions 1..5 still decode; versions 6 and 7 are coder
// 3's, 8 coder 2's alone (its own header: spatial_coder.js).
const STREAM_VERSION = 5;
const TABLE_STREAM_VERSION = 6;
const PREFIX_REFS_STREAM_VERSION = 7;  // coder 3, references in the prefix section
const isTableVersion = (v) => v === TABLE_STREAM_VERSION || v === PREFIX_REFS_STREAM_VERSION;
const CODER_ZSTD = 0;
const CODER_CONTEXT = 1;
const CODER_SPATIAL = 2;
const CODER_TABLE = 3;
// A coded bit costs at least 0.0014 bits and a node one 8-bit mask: a byte holds < 720 nodes
// (coder 1); coder 2 codes at least 7 bits a mask: < 820; coder 3 at least 1 bit a mask: 8.
const MAX_CONTEXT_NODES_PER_BYTE = 720;
const MAX_SPATIAL_NODES_PER_BYTE = 820;
const MAX_TABLE_NODES_PER_BYTE = 8;

// Context classes: internal nodes by height (3..21), brick cell masks (2), brick voxel masks (1).
const VOXEL_CLASS = 1;
const BRICK_CELL_CLASS = 2;
const CLASSES = MAX_DEPTH + 1;
const MASK_BASE = 0;
const FLAG_BASE = CLASSES * 256;
const REF_BASE = FLAG_BASE + CLASSES;
const MODEL_COUNT = REF_BASE + CLASSES * GAMMA_MODELS;
// Coder 3's range-coded section adds: whether a class sends code lengths, and the lengths' 4-bit
// trees by the previous symbol's length.
const TABLE_CODED = MODEL_COUNT;
const LENGTH_BASE = TABLE_CODED + 1;
const TABLE_MODEL_COUNT = LENGTH_BASE + (PREFIX_CODE_BITS + 1) * bitTreeModels(4);

export const popcount32 = (v) => {
  v -= (v >>> 1) & 0x55555555;
  v = (v & 0x33333333) + ((v >>> 2) & 0x33333333);
  return (Math.imul((v + (v >>> 4)) & 0x0f0f0f0f, 0x01010101) >>> 24);
};
const POPCOUNT8 = Uint8Array.from({ length: 256 }, (_, i) => popcount32(i));

// Mipmap count of a brick: itself, its occupied 2x2x2 cells, its voxels.
function brickMipCount(lo, hi) {
  let cells = 0;
  for (let c = 0; c < 4; ++c) cells += ((lo >>> (8 * c)) & 0xff ? 1 : 0) + ((hi >>> (8 * c)) & 0xff ? 1 : 0);
  return 1 + cells + popcount32(lo) + popcount32(hi);
}

// Coder 1's masks: a bit tree per class in the range-coded stream.
class ContextMasks {
  constructor(rc, p) {
    this.rc = rc;
    this.p = p;
  }
  mask(cls) {
    return this.rc.bitTree(this.p, MASK_BASE + cls * 256, 8);
  }
  overrun() {
    return false;  // the range decoder's own
  }
}

// A code's lengths from `rc` as code_lengths.cc ReadCodeLengths reads them (symbols first..255).
function readCodeLengths(rc, p, first, what) {
  const lengths = new Uint8Array(256);
  const coded = rc.bit(p, TABLE_CODED);
  let previous = 0;
  for (let s = first; s < 256; ++s) {
    lengths[s] = coded ? rc.bitTree(p, LENGTH_BASE + previous * bitTreeModels(4), 4) : 8;
    if (lengths[s] > PREFIX_CODE_BITS) throw corrupt(`geometry stream holds a ${what} code longer than 12 bits`);
    previous = lengths[s];
  }
  return lengths;
}

// Coder 3's masks: a canonical prefix code per class 1..depth, its lengths read from `rc` (the
// range-coded section) as table_coder.cc writes them; the masks follow the section. Version 7: then
// the references' code, the references read from the prefix section too (TableSource::Ref).
class TableMasks {
  constructor(rc, p, bytes, start, depth, prefixRefs) {
    this.tables = [null];
    for (let cls = 1; cls <= depth; ++cls) this.tables.push(buildPrefixTable(readCodeLengths(rc, p, 1, 'mask')));
    this.refTable = prefixRefs ? buildPrefixTable(readCodeLengths(rc, p, 0, 'reference')) : null;
    if (rc.overrun()) throw corrupt('geometry stream ends inside its code tables');
    this.bits = new PrefixDecoder(bytes, start, bytes.length);
  }
  // Version 7: a reference below `bound` (k + 1 = v as its length class and two top bits, then the
  // rest raw), or `bound` where the symbol is no code or no length class of `bound`.
  ref(bound) {
    const s = this.bits.get(this.refTable);
    const length = bitWidth(bound) - (s >> 2);
    const top = Math.min(length - 1, 2);
    if (s < 0 || length < 1 || (s & 3) >> top) return bound;
    const high = (1 << top) | (s & 3);
    return high * 2 ** (length - 1 - top) + this.bits.bits(length - 1 - top) - 1;
  }
  mask(cls) {
    const s = this.bits.get(this.tables[cls]);
    return s < 0 ? 0 : s;
  }
  overrun() {
    return this.bits.overrun();
  }
}

function readSymbols(rc, p, source, depth, mode, counts) {
  const levels = depth - 2;
  const masks = [];
  const firstChild = [];
  const children = [];
  for (let level = 0; level < levels; ++level) {
    const cls = depth - level;
    const n = counts[level];
    const levelMasks = new Uint8Array(n);
    const first = new Uint32Array(n + 1);
    const kids = new GrowableU32(Math.min(8 * n, 2 * counts[level + 1]));
    const flagModel = FLAG_BASE + cls;
    const refBase = REF_BASE + cls * GAMMA_MODELS;
    const nextCount = counts[level + 1];
    const prefixRefs = source.refTable != null;
    let seen = 0;
    for (let i = 0; i < n; ++i) {
      const mask = source.mask(cls);
      if (mask === 0 || rc.overrun() || source.overrun()) throw corrupt('geometry stream holds an empty or missing node mask');
      levelMasks[i] = mask;
      first[i] = kids.n;
      for (let c = POPCOUNT8[mask]; c > 0; --c) {
        let k;
        if (seen > 0 && rc.bit(p, flagModel)) {
          k = prefixRefs ? source.ref(seen) : rc.gamma(p, refBase, bitWidth(seen)) - 1;
          if (k >= seen) throw corrupt('geometry stream refers to a node not yet seen');
        } else {
          k = seen++;
          if (seen > nextCount) throw corrupt('geometry stream holds more nodes than its header declares');
        }
        kids.push(k);
      }
    }
    first[n] = kids.n;
    if (seen !== nextCount) throw corrupt('geometry stream holds fewer nodes than its header declares');
    masks.push(levelMasks);
    firstChild.push(first);
    children.push(kids.done());
  }
  const bricks = counts[levels];
  const brickLo = new Uint32Array(bricks);
  const brickHi = new Uint32Array(bricks);
  for (let i = 0; i < bricks; ++i) {
    const cells = source.mask(BRICK_CELL_CLASS);
    if (cells === 0) throw corrupt('geometry stream holds an empty brick');
    let lo = 0;
    let hi = 0;
    for (let c = 0; c < 8; ++c) {
      if (!((cells >> c) & 1)) continue;
      const voxels = source.mask(VOXEL_CLASS);
      if (voxels === 0) throw corrupt('geometry stream holds an empty brick cell');
      if (c < 4) lo |= voxels << (8 * c);
      else hi |= voxels << (8 * (c - 4));
    }
    brickLo[i] = lo;
    brickHi[i] = hi;
  }
  if (rc.overrun() || source.overrun()) throw corrupt('geometry stream ends early');
  return { depth, mode, levels, masks, firstChild, children, brickLo, brickHi };
}

// Counts bottom-up: count[L][i] by the mode, voxels[L][i] the voxels below node i.
function addCounts(dag) {
  const { levels, mode, brickLo, brickHi } = dag;
  const mip = mode === COUNT_MIPMAP;
  const brickCount = new Float64Array(brickLo.length);
  const brickVoxels = new Float64Array(brickLo.length);
  for (let i = 0; i < brickLo.length; ++i) {
    brickVoxels[i] = popcount32(brickLo[i]) + popcount32(brickHi[i]);
    brickCount[i] = mip ? brickMipCount(brickLo[i], brickHi[i]) : brickVoxels[i];
  }
  dag.count = new Array(levels);
  dag.voxels = new Array(levels);
  let belowCount = brickCount;
  let belowVoxels = brickVoxels;
  for (let level = levels - 1; level >= 0; --level) {
    const first = dag.firstChild[level];
    const kids = dag.children[level];
    const n = dag.masks[level].length;
    const count = new Float64Array(n);
    const voxels = new Float64Array(n);
    for (let i = 0; i < n; ++i) {
      let sum = mip ? 1 : 0;
      let v = 0;
      for (let c = first[i]; c < first[i + 1]; ++c) {
        sum += belowCount[kids[c]];
        v += belowVoxels[kids[c]];
      }
      count[i] = sum;
      voxels[i] = v;
    }
    dag.count[level] = count;
    dag.voxels[level] = voxels;
    belowCount = count;
    belowVoxels = voxels;
  }
  dag.rootCount = belowCount[0];
  dag.rootVoxels = belowVoxels[0];
  // The limits of the resident C++ DAG: 32-bit node words, and 32-bit counts on the levels with
  // depth - level >= 8 (the root's count is the largest).
  let words = 0;
  for (let level = 0; level < levels; ++level) words += dag.masks[level].length + dag.children[level].length;
  if (words > 0xffffffff) throw resourceLimit('decoded DAG exceeds 2^32 node words');
  if (dag.depth >= 8 && dag.rootCount > 0xffffffff) throw resourceLimit('decoded DAG holds more than 2^32 voxels');
}

// `maxNodes` bounds what a lying level table may make the decoder allocate (nodes + bricks).
export function decodeDag(bytes, maxNodes) {
  if (bytes.length > 0 && bytes[0] === COMPACT_SPATIAL_VERSION) {
    const dag = decodeCompactSpatial(bytes, maxNodes);
    addCounts(dag);
    return dag;
  }
  if (bytes.length < 4) throw corrupt('geometry stream is shorter than its 4-byte header');
  if (!(bytes[0] >= 1 && bytes[0] <= PREFIX_REFS_STREAM_VERSION)) throw corrupt(`geometry stream version ${bytes[0]} is unknown`);
  if (bytes[1] > CODER_TABLE) throw corrupt(`geometry stream names unknown coder ${bytes[1]}`);
  if ((bytes[1] === CODER_TABLE) !== isTableVersion(bytes[0])) {
    throw corrupt(`geometry stream version ${bytes[0]} names coder ${bytes[1]}: coder 3 is versions 6 and 7's, and they are coder 3's`);
  }
  const depth = bytes[2];
  if (depth < 2 || depth > MAX_DEPTH) throw corrupt(`geometry stream depth ${depth} is outside 2..21`);
  if (bytes[3] > 1) throw corrupt(`geometry stream names unknown count mode ${bytes[3]}`);
  const mode = bytes[3];

  const cursor = { pos: 4 };
  const counts = new Array(depth - 1);
  let total = 0;
  for (let level = 0; level < counts.length; ++level) {
    const c = readVarint(bytes, cursor);
    if (c < 0) throw corrupt('geometry stream ends inside its level table');
    if (c === 0 || c > maxNodes - total) throw corrupt('geometry stream declares more nodes than its voxels allow');
    // A node has at most 8 children: a level holds at most 8 times the nodes of the one above.
    if (level > 0 && c > 8 * counts[level - 1]) throw corrupt('geometry stream declares an impossible node count');
    counts[level] = c;
    total += c;
  }
  if (counts[0] !== 1) throw corrupt('geometry stream must have exactly one root');
  if (bytes[1] === CODER_ZSTD) throw unsupported('the geometry stream is zstd-coded; this decoder reads the range coders only');
  const payload = bytes.length - cursor.pos + 8;  // + the zero bytes the decoder may read past the end
  const perByte = bytes[1] === CODER_CONTEXT ? MAX_CONTEXT_NODES_PER_BYTE
    : bytes[1] === CODER_TABLE ? MAX_TABLE_NODES_PER_BYTE : MAX_SPATIAL_NODES_PER_BYTE;
  if (total > payload * perByte) {
    throw corrupt(`geometry stream declares ${total} nodes, more than its ${bytes.length - cursor.pos} bytes can hold`);
  }
  let dag;
  if (bytes[1] === CODER_TABLE) {
    const section = readVarint(bytes, cursor);
    if (section < 0) throw corrupt('geometry stream ends inside its section length');
    if (section > bytes.length - cursor.pos) throw corrupt('geometry stream is shorter than its section length says');
    const end = cursor.pos + section;
    const rc = new RangeDecoder(bytes, cursor.pos, end);
    const p = newModels(TABLE_MODEL_COUNT);
    dag = readSymbols(rc, p, new TableMasks(rc, p, bytes, end, depth, bytes[0] === PREFIX_REFS_STREAM_VERSION), depth, mode, counts);
  } else {
    const rc = new RangeDecoder(bytes, cursor.pos);
    if (bytes[1] === CODER_CONTEXT) {
      const p = newModels(MODEL_COUNT);
      dag = readSymbols(rc, p, new ContextMasks(rc, p), depth, mode, counts);
    } else {
      dag = { ...decodeSpatial(rc, depth, counts, bytes[0], maxNodes), mode };
    }
  }
  addCounts(dag);
  return dag;
}
