#include "pointdag/color/weight_context.h"

#include <algorithm>
#include <array>

#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

// The Morton bits of each axis (x: bits 3i+2, y: 3i+1, z: 3i).
constexpr std::array<uint64_t, 3> kAxisBits = {0x4924924924924924ull, 0x2492492492492492ull, 0x1249249249249249ull};

// One axis' interleaved bits of the coordinate moved by -1, 0, +1 (within `axis` only: a carry
// or borrow runs through the other axes' bits and is masked away); false where it leaves 0..2^21-1.
struct Moved {
  std::array<uint64_t, 3> bits;
  std::array<bool, 3> valid;
};

Moved Move(uint64_t code, uint64_t axis) {
  const uint64_t own = code & axis;
  return {{((own - 1) & axis), own, ((own | ~axis) + 1) & axis}, {own != 0, true, own != axis}};
}

}  // namespace

WeightContexts::WeightContexts(std::span<const uint64_t> morton) : morton_(morton), table_(morton), decoded_(morton.size()) {}

uint32_t WeightContexts::Of(uint64_t i, const Endpoints& ends, int bits, uint32_t prev) const {
  const int64_t m = (1 << bits) - 1;
  const int32_t s[3] = {ends.b.r - ends.a.r, ends.b.g - ends.a.g, ends.b.b - ends.a.b};
  const int64_t len2 = int64_t{s[0]} * s[0] + int64_t{s[1]} * s[1] + int64_t{s[2]} * s[2];
  const uint64_t code = morton_[i];
  const Moved x = Move(code, kAxisBits[0]), y = Move(code, kAxisBits[1]), z = Move(code, kAxisBits[2]);
  int64_t sum = 0, total = 0;
  for (int dx = 0; dx < 3; ++dx) {
    for (int dy = 0; dy < 3; ++dy) {
      for (int dz = 0; dz < 3; ++dz) {
        if (!x.valid[dx] || !y.valid[dy] || !z.valid[dz]) continue;
        const uint64_t near = x.bits[dx] | y.bits[dy] | z.bits[dz];
        if (near >= code) continue;  // itself, or not decoded yet
        const int64_t j = table_.Find(near);
        if (j < 0) continue;
        const Rgb8 c = decoded_[static_cast<size_t>(j)];
        const int64_t dot = int64_t{c.r - ends.a.r} * s[0] + int64_t{c.g - ends.a.g} * s[1] + int64_t{c.b - ends.a.b} * s[2];
        // The nearest weight step, clamped to 0..m; 0 on a block whose endpoints are equal.
        const int64_t step = dot <= 0 || len2 == 0 ? 0 : std::min<int64_t>(m, (2 * dot * m + len2) / (2 * len2));
        const int64_t weight = 8 >> ((dx != 1) + (dy != 1) + (dz != 1));  // faces 4, edges 2, corners 1
        sum += weight * step;
        total += weight;
      }
    }
  }
  if (total == 0) return 16 + prev;
  return static_cast<uint32_t>((2 * sum + total) / (2 * total));
}

}  // namespace pointdag
