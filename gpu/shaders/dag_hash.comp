#version 450
#extension GL_GOOGLE_include_directive : require
// DAG level, step 3, one invocation per run of cells: each cell's subtree hash, XXH3-64 with seed 0
// and the default secret, for the input lengths the DAG uses: 8 bytes (a brick's mask) and
// 8 (1 + n) bytes (a node's mask and its n children's hashes).
#include "dag_common.glsl"
layout(local_size_x = 64) in;

// The first 128 bytes of XXH3's default secret, as little-endian 64-bit words.
const uint64_t kSecret[16] = uint64_t[16](
    0xBE4BA423396CFEB8ul, 0x1CAD21F72C81017Cul, 0xDB979083E96DD4DEul, 0x1F67B3B7A4A44072ul,
    0x78E5C0CC4EE679CBul, 0x2172FFCC7DD05A82ul, 0x8E2443F7744608B8ul, 0x4C263A81E69035E0ul,
    0xCB00C391BB52283Cul, 0xA32E531B8B65D088ul, 0x4EF90DA297486471ul, 0xD8ACDEA946EF1938ul,
    0x3F349CE33F76FAA8ul, 0x1D4F0BC7C7BBDCF9ul, 0x3159B4CD4BE0518Aul, 0x647378D9C97E9FC8ul);
const uint64_t kPrime64_1 = 0x9E3779B185EBCA87ul;
const uint64_t kPrimeMx1 = 0x165667919E3779F9ul;
const uint64_t kPrimeMx2 = 0x9FB21C651E98DF25ul;

uint64_t Rotl(uint64_t x, uint r) { return (x << r) | (x >> (64u - r)); }
uint Swap32(uint x) { return (x << 24) | ((x & 0xFF00u) << 8) | ((x >> 8) & 0xFF00u) | (x >> 24); }
uint64_t Swap64(uint64_t x) { return (uint64_t(Swap32(uint(x))) << 32) | uint64_t(Swap32(uint(x >> 32))); }

// The 128-bit product's halves XORed (XXH3_mul128_fold64), from 32-bit limbs.
uint64_t MulFold(uint64_t a, uint64_t b) {
  const uint64_t a0 = a & 0xFFFFFFFFul, a1 = a >> 32, b0 = b & 0xFFFFFFFFul, b1 = b >> 32;
  const uint64_t lo_lo = a0 * b0, hi_lo = a1 * b0, lo_hi = a0 * b1, hi_hi = a1 * b1;
  const uint64_t cross = (lo_lo >> 32) + (hi_lo & 0xFFFFFFFFul) + lo_hi;
  const uint64_t upper = (hi_lo >> 32) + (cross >> 32) + hi_hi;
  const uint64_t lower = (cross << 32) | (lo_lo & 0xFFFFFFFFul);
  return lower ^ upper;
}

uint64_t Avalanche(uint64_t h) {
  h ^= h >> 37;
  h *= kPrimeMx1;
  return h ^ (h >> 32);
}

// XXH3_len_4to8_64b for the 8 bytes of v.
uint64_t Hash8(uint64_t v) {
  const uint64_t bitflip = kSecret[1] ^ kSecret[2];
  uint64_t h = ((v >> 32) + (v << 32)) ^ bitflip;  // input2 + (input1 << 32)
  h ^= Rotl(h, 49) ^ Rotl(h, 24);
  h *= kPrimeMx2;
  h ^= (h >> 35) + 8ul;
  h *= kPrimeMx2;
  return h ^ (h >> 28);
}

uint64_t g_mask;
uint g_first;
// Word w of a node's hash input: its mask, then its children's hashes.
uint64_t Word(uint w) { return w == 0u ? g_mask : below_hashes[g_first + w - 1u]; }
uint64_t Mix16(uint word, uint secret) { return MulFold(Word(word) ^ kSecret[secret], Word(word + 1u) ^ kSecret[secret + 1u]); }

// XXH3 of that many 64-bit words (2..9), lengths 16 (len_9to16) and 24..72 (len_17to128).
uint64_t HashWords(uint words) {
  const uint64_t len = uint64_t(words) * 8ul;
  if (words == 2u) {
    const uint64_t lo = Word(0u) ^ (kSecret[3] ^ kSecret[4]), hi = Word(1u) ^ (kSecret[5] ^ kSecret[6]);
    return Avalanche(len + Swap64(lo) + hi + MulFold(lo, hi));
  }
  uint64_t acc = len * kPrime64_1;
  if (len > 32ul) {
    if (len > 64ul) acc += Mix16(4u, 8u) + Mix16(words - 6u, 10u);
    acc += Mix16(2u, 4u) + Mix16(words - 4u, 6u);
  }
  acc += Mix16(0u, 0u) + Mix16(words - 2u, 2u);
  return Avalanche(acc);
}

void main() {
  // A cell has at most 2^shift entries below: kTile >> shift cells walk at most kTile of them.
  const uint per_invocation = kTile >> params.shift;
  const uint first_cell = gl_GlobalInvocationID.x * per_invocation, cells = counts[params.tiles];
  for (uint cell = first_cell; cell < min(cells, first_cell + per_invocation); ++cell) {
    const uint begin = firsts[cell], end = cell + 1u < cells ? firsts[cell + 1u] : params.count;
    g_mask = 0ul;
    g_first = begin;
    const uint bits = params.shift == 6u ? 63u : 7u;
    for (uint i = begin; i < end; ++i) g_mask |= 1ul << uint(below_keys[i] & uint64_t(bits));
    hashes[cell] = params.shift == 6u ? Hash8(g_mask) : HashWords(1u + end - begin);
  }
}
