#include "pointdag/color/weight_context.h"

#include <algorithm>
#include <bit>
#include <cstddef>

namespace pointdag {
namespace {

// The Morton bits of each axis (x: bits 3i+2, y: 3i+1, z: 3i).
constexpr std::array<uint64_t, 3> kAxisBits = {0x4924924924924924ull, 0x2492492492492492ull, 0x1249249249249249ull};

// A code with one axis' coordinate moved by -1, 0, +1 (a borrow or carry runs through the other
// axes' bits and is masked away); false where it leaves 0..2^21-1.
bool Moved(uint64_t code, int axis, int delta, uint64_t& out) {
  const uint64_t bits = kAxisBits[axis], own = code & bits;
  if ((delta < 0 && own == 0) || (delta > 0 && own == (bits >> 6))) return false;  // brick codes: 19 bits an axis
  const uint64_t moved = delta < 0 ? (own - 1) & bits : delta > 0 ? ((own | ~bits) + 1) & bits : own;
  out = moved | (code & ~bits);
  return true;
}

// Position of local cell (x, y, z), each 0..3, in its brick's 64-bit mask (Morton order).
constexpr int BrickBit(int x, int y, int z) {
  const auto spread = [](int v) { return (v & 1) | (v & 2) << 2; };
  return spread(x) << 2 | spread(y) << 1 | spread(z);
}

}  // namespace

WeightContexts::WeightContexts(std::span<const uint64_t> morton) : morton_(morton), decoded_(morton.size()) {
  for (size_t i = 0; i < morton.size(); ++i) {
    const uint64_t code = morton[i] >> 6;
    if (bricks_.empty() || bricks_.back().code != code) bricks_.push_back({code, static_cast<uint32_t>(i), 0});
    bricks_.back().mask |= uint64_t{1} << (morton[i] & 63);
  }
  if (!bricks_.empty()) EnterBrick(0);
}

void WeightContexts::EnterBrick(size_t k) {
  current_ = k;
  const uint64_t code = bricks_[k].code;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        Brick& near = near_[(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)];
        near = {0, 0, 0};
        uint64_t c = code;
        if (!Moved(c, 0, dx, c) || !Moved(c, 1, dy, c) || !Moved(c, 2, dz, c) || c > code) continue;  // after this brick
        // Bricks are sorted by code: the neighbour, if any, is at or before this one.
        const auto first = bricks_.begin(), last = bricks_.begin() + static_cast<ptrdiff_t>(k) + 1;
        const auto it = std::lower_bound(first, last, c, [](const Brick& b, uint64_t v) { return b.code < v; });
        if (it != last && it->code == c) near = *it;
      }
    }
  }
}

uint32_t WeightContexts::Of(uint64_t i, const Endpoints& ends, int bits, uint32_t prev) {
  size_t k = current_;
  while (k + 1 < bricks_.size() && bricks_[k + 1].start <= i) ++k;
  if (k != current_) EnterBrick(k);

  const int own = static_cast<int>(morton_[i] & 63);
  const int lx = (own >> 2 & 1) | (own >> 4 & 2), ly = (own >> 1 & 1) | (own >> 3 & 2), lz = (own & 1) | (own >> 2 & 2);
  int64_t r = 0, g = 0, b = 0, total = 0;  // the neighbours' colors, weighted
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        if (dx >= 0 && dy >= 0 && dz >= 0) continue;  // itself, or after it (the code grows with each coordinate)
        const int nx = lx + dx, ny = ly + dy, nz = lz + dz;
        const Brick& near = near_[((nx >> 2) + 1) * 9 + ((ny >> 2) + 1) * 3 + ((nz >> 2) + 1)];  // >> 2: -1, 0 or 1
        const int bit = BrickBit(nx & 3, ny & 3, nz & 3);
        if (!(near.mask >> bit & 1)) continue;
        if (&near == &near_[13] && bit > own) continue;  // later in this brick
        const Rgb8 c = decoded_[near.start + static_cast<size_t>(std::popcount(near.mask & ((uint64_t{1} << bit) - 1)))];
        const int weight = 8 >> ((dx != 0) + (dy != 0) + (dz != 0));  // faces 4, edges 2, corners 1
        r += weight * c.r;
        g += weight * c.g;
        b += weight * c.b;
        total += weight;
      }
    }
  }
  if (total == 0) return 16 + prev;
  // Their mean's position on the segment A -> B in weight steps, rounded, clamped to 0..m (0 where
  // A = B): one division per weight, not one per neighbour.
  const int64_t m = (1 << bits) - 1;
  const int64_t sr = ends.b.r - ends.a.r, sg = ends.b.g - ends.a.g, sb = ends.b.b - ends.a.b;
  const int64_t len2 = sr * sr + sg * sg + sb * sb;
  const int64_t dot = (r - total * ends.a.r) * sr + (g - total * ends.a.g) * sg + (b - total * ends.a.b) * sb;
  if (dot <= 0 || len2 == 0) return 0;
  return static_cast<uint32_t>(std::min(m, (2 * dot * m + total * len2) / (2 * total * len2)));
}

}  // namespace pointdag
