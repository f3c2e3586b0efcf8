// The .pdag container (proto/PDAG_FORMAT.md §1), checked as codec/pointdag/container/pdag_file.cc
// ParsePdag checks it, in the same order: header, header CRC, size, then each section's bounds and
// CRC32C before any of its bytes is used. Section payloads are views into `bytes`, never copies.
import { crc32c } from './crc32c.js';
import { parseJson } from './json_text.js';
import { corrupt, unsupported } from './pdag_error.js';

const MAGIC = [0x50, 0x44, 0x41, 0x47, 0x0d, 0x0a, 0x1a, 0x0a];
const HEADER_SIZE = 32;
const ENTRY_SIZE = 32;
const MAX_SECTIONS = 64;
const MAJOR_VERSION = 1;
const ZERO4 = new Uint8Array(4);

// A little-endian u64 as a number: exact below 2^53, and above it still larger than any file.
const u64 = (view, at) => view.getUint32(at, true) + view.getUint32(at + 4, true) * 4294967296;

function tagString(bytes, at) {
  let end = at;
  while (end < at + 8 && bytes[end] !== 0) ++end;
  return String.fromCharCode(...bytes.subarray(at, end));
}

// -> {meta: JsonDocument, geometry: Uint8Array, colors: Uint8Array | null (absent or empty)}
export function parsePdagContainer(bytes) {
  if (bytes.length < HEADER_SIZE) throw corrupt('file is shorter than the 32-byte .pdag header');
  for (let i = 0; i < 8; ++i) if (bytes[i] !== MAGIC[i]) throw corrupt('not a .pdag file (wrong magic)');
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const major = view.getUint16(8, true);
  const minor = view.getUint16(10, true);
  if (major !== MAJOR_VERSION) {
    throw unsupported(`.pdag version ${major}.${minor} is not supported (this build reads version 1.x)`);
  }
  const count = view.getUint32(12, true);
  const headerCrc = view.getUint32(16, true);
  if (count === 0 || count > MAX_SECTIONS) throw corrupt(`.pdag declares ${count} sections`);
  const tableEnd = HEADER_SIZE + ENTRY_SIZE * count;
  if (bytes.length < tableEnd) throw corrupt('.pdag ends inside its section table');
  // The header CRC covers the header with its own field taken as zero, and the table.
  const crc = crc32c(bytes.subarray(20, tableEnd), crc32c(ZERO4, crc32c(bytes.subarray(0, 16))));
  if (crc !== headerCrc) throw corrupt('.pdag header CRC mismatch');
  const total = u64(view, 24);
  if (total !== bytes.length) throw corrupt(`.pdag header says the file has ${total} bytes, it has ${bytes.length}`);

  let meta = null;
  let geometry = null;
  let colors = null;
  for (let i = 0; i < count; ++i) {
    const e = HEADER_SIZE + ENTRY_SIZE * i;
    const tag = tagString(bytes, e);
    const offset = u64(view, e + 8);
    const length = u64(view, e + 16);
    if (offset < tableEnd || offset > bytes.length || length > bytes.length - offset) {
      throw corrupt(`.pdag section '${tag}' lies outside the file`);
    }
    const data = bytes.subarray(offset, offset + length);
    if (crc32c(data) !== view.getUint32(e + 24, true)) throw corrupt(`.pdag section '${tag}' fails its CRC32C check`);
    if ((tag === 'meta' && meta) || (tag === 'geometry' && geometry) || (tag === 'colors' && colors)) {
      throw corrupt(`.pdag holds section '${tag}' twice`);
    }
    if (tag === 'meta') {
      try {
        meta = parseJson(data);
      } catch (err) {
        throw corrupt(`.pdag metadata is ${err.detail}`);
      }
      const root = meta.root;
      if (typeof root !== 'object' || root === null || Array.isArray(root)) throw corrupt('.pdag metadata is not a JSON object');
    } else if (tag === 'geometry') {
      geometry = data;
    } else if (tag === 'colors' && length > 0) {
      colors = data;  // an empty colors section is no colors, as in the C++ reader
    }  // unknown sections are skipped: later minor versions may add some
  }
  if (!meta || !geometry) throw corrupt('.pdag lacks its meta or geometry section');
  return { meta, geometry, colors };
}
