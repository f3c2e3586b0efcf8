// LEB128 unsigned integers (codec/pointdag/entropy/varint.h): 7 bits a byte, low first, at most
// 64 bits (bits past the 64th are dropped, as the C++ shift drops them).
// Returns the value (a number: exact below 2^53, which every limit it meets is) or -1 when the
// input ends first or the varint runs past 10 bytes. `cursor.pos` advances.
export function readVarint(bytes, cursor) {
  let v = 0;
  let pos = cursor.pos;
  for (let shift = 0; shift < 64; shift += 7) {
    if (pos >= bytes.length) return -1;
    const b = bytes[pos++];
    if (shift < 49) {
      v += (b & 0x7f) * 2 ** shift;
    } else {
      v = Number(BigInt.asUintN(64, BigInt(v) + (BigInt(b & 0x7f) << BigInt(shift))));
    }
    if (!(b & 0x80)) {
      cursor.pos = pos;
      return v;
    }
  }
  return -1;
}
