// CRC-32C (Castagnoli, reflected 0x82F63B78), slice-by-4 as codec/pointdag/container/crc32c.cc.
const TABLES = (() => {
  const t = new Uint32Array(4 * 256);
  for (let i = 0; i < 256; ++i) {
    let c = i;
    for (let k = 0; k < 8; ++k) c = (c >>> 1) ^ (0x82f63b78 & -(c & 1));
    t[i] = c >>> 0;
  }
  for (let i = 0; i < 256; ++i) {
    for (let s = 1; s < 4; ++s) t[s * 256 + i] = (t[(s - 1) * 256 + i] >>> 8) ^ t[t[(s - 1) * 256 + i] & 0xff];
  }
  return t;
})();

// `crc` continues an earlier checksum: crc32c(b, crc32c(a)) === crc32c(a ++ b).
export function crc32c(bytes, crc = 0) {
  const t = TABLES;
  let c = ~crc;
  let i = 0;
  const n4 = bytes.length & ~3;
  for (; i < n4; i += 4) {
    c ^= bytes[i] | (bytes[i + 1] << 8) | (bytes[i + 2] << 16) | (bytes[i + 3] << 24);
    c = t[768 + (c & 0xff)] ^ t[512 + ((c >>> 8) & 0xff)] ^ t[256 + ((c >>> 16) & 0xff)] ^ t[c >>> 24];
  }
  for (; i < bytes.length; ++i) c = (c >>> 8) ^ t[(c ^ bytes[i]) & 0xff];
  return ~c >>> 0;
}
