// Writers of per-tile shadow layers (proto/SHADOW_FORMAT.md §2) for the tests: a valid layer of any
// light values (version 1: maximal runs; version 2: as the C++ writer, a run of every stretch of 3 or
// more equal bytes, literal strings of the rest), and a frame with a correct CRC-32C around any run bytes, so that a
// hostile case reaches the check it aims at rather than the CRC.
import { crc32c } from '../../../web/src/decoder/crc32c.js';
import { varint } from './pdag_writer.mjs';

// The runs of `light`: value, then length - 1 as a varint, one per maximal run.
export function shadowRuns(light) {
  const out = [];
  for (let i = 0; i < light.length;) {
    let j = i + 1;
    while (j < light.length && light[j] === light[i]) ++j;
    out.push(light[i], ...varint(j - i - 1));
    i = j;
  }
  return Uint8Array.from(out);
}

// header fields may lie: {magic, version, kind, samples, count}; the CRC is that of `runs` unless `crc` is given.
export function frameShadowLayer(runs, { magic = 'PDSH', version = 1, kind = 0, samples = 1, count, crc } = {}) {
  const out = new Uint8Array(16 + runs.length);
  const v = new DataView(out.buffer);
  for (let i = 0; i < 4; ++i) out[i] = magic.charCodeAt(i);
  out[4] = version;
  out[5] = kind;
  v.setUint16(6, samples, true);
  v.setUint32(8, count, true);
  v.setUint32(12, crc ?? crc32c(runs), true);
  out.set(runs, 16);
  return out;
}

// Version 2's tokens: varint 2(len - 1) then the value for a run, varint 2(len - 1) + 1 then the bytes for literals.
const MIN_RUN = 3;
export function shadowTokens(light) {
  const out = [];
  let literals = [];
  const flush = () => {
    if (literals.length) out.push(...varint(2 * (literals.length - 1) + 1), ...literals);
    literals = [];
  };
  for (let i = 0; i < light.length;) {
    let j = i + 1;
    while (j < light.length && light[j] === light[i]) ++j;
    if (j - i >= MIN_RUN) {
      flush();
      out.push(...varint(2 * (j - i - 1)), light[i]);
    } else {
      for (let k = i; k < j; ++k) literals.push(light[k]);
    }
    i = j;
  }
  flush();
  return Uint8Array.from(out);
}

export function encodeShadowLayer(light, { kind = 0, samples = 1, version = 1 } = {}) {
  const body = version === 1 ? shadowRuns(light) : shadowTokens(light);
  return frameShadowLayer(body, { kind, samples, count: light.length, version });
}
