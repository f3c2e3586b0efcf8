#include "pointdag/dag/spatial_context.h"

namespace pointdag {

Level Expand(const Level& cur, int level, int levels, const DagArrays& a, bool positions) {
  std::vector<int32_t> base(cur.size(), -1);
  int32_t total = 0;
  for (size_t i = 0; i < cur.size(); ++i) {
    if (level >= levels || cur.first[i]) {
      base[i] = total;
      total += kByteBits[cur.mask[i]];
    }
  }
  Level next;
  next.id.resize(total);
  next.first.resize(total);
  next.parent.resize(total);
  next.nbr.reserve(total + 1);
  next.nbr.resize(total);
  if (positions) next.pos.resize(total);
  uint32_t fresh = 0;  // new ordinals assigned so far: ordinals are numbered in this order
  int32_t j = 0;
  for (size_t i = 0; i < cur.size(); ++i) {
    if (base[i] < 0) continue;
    const unsigned mask = cur.mask[i];
    // Per side, the cell whose children lie there (outside: the neighbour; mask 0 unless expanded).
    std::array<int32_t, 6> side_base;
    std::array<unsigned, 6> side_mask;
#pragma GCC unroll 6
    for (int d = 0; d < 6; ++d) {
      const int32_t owner = cur.nbr[i][d];
      const bool expanded = owner >= 0 && base[owner] >= 0;
      side_base[d] = expanded ? base[owner] : 0;
      side_mask[d] = expanded ? cur.mask[owner] : 0u;
    }
    for (int c = 0, r = 0; c < 8; ++c) {
      if (!((mask >> c) & 1u)) continue;
      uint32_t id;
      bool is_first;
      if (level + 1 == levels) {
        id = cur.kids[i] + static_cast<uint32_t>(r);  // brick slot
        is_first = true;
      } else if (level < levels) {
        id = a.children[level][cur.kids[i] + r];
        is_first = id == fresh;
        if (is_first) ++fresh;
      } else {
        id = cur.id[i] * 8 + static_cast<uint32_t>(c);
        is_first = cur.first[i];
      }
      ++r;
      auto& n = next.nbr[j];
#pragma GCC unroll 6  // constant d: its axis bit and side fold into the code
      for (int d = 0; d < 6; ++d) {
        const int bit = 4 >> (d / 2);
        const bool inside = (d & 1) ? !(c & bit) : (c & bit);
        const int sib = c ^ bit;
        const unsigned owner_mask = inside ? mask : side_mask[d];
        const int32_t owner_base = inside ? base[i] : side_base[d];
        n[d] = ((owner_mask >> sib) & 1u) ? owner_base + Rank(owner_mask, sib) : -1;
      }
      next.id[j] = id;
      next.first[j] = is_first ? 1 : 0;
      next.parent[j] = static_cast<uint8_t>(mask);
      if (positions) {
        const auto& p = cur.pos[i];
        next.pos[j] = {2 * p[0] + ((c >> 2) & 1u), 2 * p[1] + ((c >> 1) & 1u), 2 * p[2] + (c & 1u)};
      }
      ++j;
    }
  }
  return next;
}

}  // namespace pointdag
