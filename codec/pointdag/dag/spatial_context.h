// Geometry coder 2's view of a cell's surroundings (proto/PDAG_FORMAT.md §2.2): the cells of one
// level in the walk's order with their face links, and what a mask bit's contexts read from them:
// the neighbours' existence and masks (versions 1, 2), the plane memory (version 4), and version 5's
// child-level pattern and parent-level neighbours on each child's side.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

#include "pointdag/bit_count.h"
#include "pointdag/dag/dag_arrays.h"

namespace pointdag {

// The cells of one level that the coder visits, in Morton order.
struct Level {
  std::vector<uint32_t> id;     // node ordinal (internal), brick index, or brick * 8 + cell
  std::vector<uint8_t> first;   // first occurrence: its mask and children are coded here
  std::vector<uint8_t> mask;    // filled as the level is coded; then a sentinel 0
  std::vector<uint8_t> parent;  // the parent's mask (version 3's mixer)
  std::vector<std::array<int32_t, 6>> nbr;  // -x, +x, -y, +y, -z, +z on this level; -1: empty or unknown; then a sentinel row
  std::vector<std::array<uint32_t, 3>> pos;  // version 4: x, y, z on this level (the plane memory)
  std::vector<uint32_t> kids;   // internal first occurrences: where their children start in DagArrays::children
  size_t size() const { return id.size(); }
  void Add(uint32_t node, bool is_first, const std::array<int32_t, 6>& n) {
    id.push_back(node);
    first.push_back(is_first ? 1 : 0);
    parent.push_back(0);
    nbr.push_back(n);
    pos.push_back({0, 0, 0});
  }
};

// The next level's cells: the children of the cells expanded here (first cells above `levels`, every
// cell from there on), with their neighbours (and with `positions`, their coordinates).
Level Expand(const Level& cur, int level, int levels, const DagArrays& a, bool positions);

inline int Rank(unsigned mask, int bit) { return kByteBits[mask & ((1u << bit) - 1)]; }

// The context's parts as tables (the same arithmetic as PDAG_FORMAT §2.2 states it, per bit):
// kSides[upper_exists << 3 | lower_exists][c]: per axis 2 = the parent's neighbour on the child's
// side exists, 1 = only the one on the other side does, 0 = neither, in base 3 (x first).
constexpr auto kSides = [] {
  std::array<std::array<uint8_t, 8>, 64> t{};
  for (unsigned e = 0; e < 64; ++e) {
    for (int c = 0; c < 8; ++c) {
      unsigned sides = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const bool up = (e >> (3 + axis)) & 1u, down = (e >> axis) & 1u;
        const bool outer = (c & (4 >> axis)) ? up : down, opposite = (c & (4 >> axis)) ? down : up;
        sides = sides * 3 + (outer ? 2 : opposite ? 1 : 0);
      }
      t[e][c] = static_cast<uint8_t>(sides);
    }
  }
  return t;
}();
// kSiblings[c][m]: the lower siblings of child c set in the mask so far (bit per axis).
constexpr auto kSiblings = [] {
  std::array<std::array<uint8_t, 256>, 8> t{};
  for (int c = 0; c < 8; ++c) {
    for (unsigned m = 0; m < 256; ++m) {
      for (int axis = 0; axis < 3; ++axis) {
        if (c & (4 >> axis)) t[c][m] = static_cast<uint8_t>(t[c][m] | ((m >> (c ^ (4 >> axis))) & 1u) << axis);
      }
    }
  }
  return t;
}();
// kFacing[axis][mask of the lower neighbour on that axis]: 4 bits per child c, its neighbour's
// child next to it (bit `axis`) when c lies on that side.
constexpr auto kFacing = [] {
  std::array<std::array<uint32_t, 256>, 3> t{};
  for (int axis = 0; axis < 3; ++axis) {
    const int a = 4 >> axis;
    for (unsigned m = 0; m < 256; ++m) {
      for (int c = 0; c < 8; ++c) {
        if (!(c & a)) t[axis][m] |= ((m >> (c | a)) & 1u) << axis << (4 * c);
      }
    }
  }
  return t;
}();

// kBitBytes[mask]: bit c of the mask as bit 0 of byte c, for building a per-child byte of all
// eight children at once.
constexpr auto kBitBytes = [] {
  std::array<uint64_t, 256> t{};
  for (unsigned m = 0; m < 256; ++m) {
    for (int c = 0; c < 8; ++c) t[m] |= uint64_t{(m >> c) & 1u} << (8 * c);
  }
  return t;
}();

// Child c's lower diagonal neighbours on its level lie at offsets −1 on the axes of o = 6, 5, 3, 7
// (xy, xz, yz, xyz): in the cell at parent offset o & ~c (bit 4 >> axis: −1 on that axis), child
// c ^ o. kDiagonalFrom[p][mask]: bit c when one of them lies in the cell at offset p != 0 and is
// set in its mask; kDiagonalSelf[c]: the bits of the mask so far that are such neighbours of c.
constexpr std::array<int, 4> kDiagonalOffsets = {6, 5, 3, 7};
constexpr auto kDiagonalFrom = [] {
  std::array<std::array<uint8_t, 256>, 8> t{};
  for (int c = 0; c < 8; ++c) {
    for (int o : kDiagonalOffsets) {
      for (unsigned m = 0; m < 256; ++m) {
        if ((o & ~c) != 0 && ((m >> (c ^ o)) & 1u)) t[o & ~c][m] = static_cast<uint8_t>(t[o & ~c][m] | 1u << c);
      }
    }
  }
  return t;
}();
constexpr auto kDiagonalSelf = [] {
  std::array<uint8_t, 8> t{};
  for (int c = 0; c < 8; ++c) {
    for (int o : kDiagonalOffsets) {
      if ((o & ~c) == 0) t[c] = static_cast<uint8_t>(t[c] | 1u << (c ^ o));
    }
  }
  return t;
}();

// Version 5's child-level pattern: for child c, its face and edge neighbours on its own level that
// are coded before it, one bit each (in the order of their offsets, x outermost, −1 first), then its
// three neighbours at −2 on x, y, z (bit c of the −x, −y, −z cells' masks). A neighbour at offset d
// lies in the cell at parent offset o (bit 4 >> axis: −1 on that axis; 0: the cell itself) as that
// cell's child `child`; it is coded before c when o != 0 and d has no +1 leaving the cell, or when
// it is a lower sibling. Corners are left out (measured: they dilute the statistics).
struct PatternBit {
  int o = 0, child = 0;
};
struct PatternLayout {
  std::array<std::array<PatternBit, 12>, 8> bits{};
  std::array<int, 8> count{};  // neighbour bits per child (6..12); the pattern has count + 3 bits
};
constexpr PatternLayout kPatternLayout = [] {
  PatternLayout t{};
  for (int c = 0; c < 8; ++c) {
    const int cc[3] = {(c >> 2) & 1, (c >> 1) & 1, c & 1};
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const int d[3] = {dx, dy, dz};
          const int moved = (dx != 0) + (dy != 0) + (dz != 0);
          if (moved == 0 || moved == 3) continue;
          PatternBit b;
          bool known = true;
          for (int a = 0; a < 3; ++a) {
            const int g = cc[a] + d[a];  // the neighbour's coordinate relative to the cell's lower corner
            if (g > 1) known = false;
            if (g < 0) b.o |= 4 >> a;
            b.child |= (g & 1) << (2 - a);
          }
          if (known && (b.o != 0 || b.child < c)) t.bits[c][t.count[c]++] = b;
        }
      }
    }
  }
  return t;
}();

// The pattern's parts as tables: kPatternSelf[c][mask so far] (the lower siblings); per lower cell
// o = 1..6, kPatternCompact[o][mask]: the bits of its children on our side (all of o's axes set), and
// kPatternFrom[o][those bits][c]: what they give child c. Small enough to stay in the L1 cache
// (a table per child and cell indexed by the whole mask was 32 kB and missed it a million times on lion).
constexpr auto kPatternSelf = [] {
  std::array<std::array<uint16_t, 256>, 8> t{};
  for (int c = 0; c < 8; ++c) {
    for (int k = 0; k < kPatternLayout.count[c]; ++k) {
      const PatternBit b = kPatternLayout.bits[c][k];
      for (unsigned m = 0; m < 256; ++m) {
        if (b.o == 0 && ((m >> b.child) & 1u)) t[c][m] = static_cast<uint16_t>(t[c][m] | 1u << k);
      }
    }
  }
  return t;
}();
constexpr auto kPatternCompact = [] {
  std::array<std::array<uint8_t, 256>, 7> t{};
  for (int o = 1; o < 7; ++o) {
    for (unsigned m = 0; m < 256; ++m) {
      int at = 0;
      for (int child = 0; child < 8; ++child) {
        if ((child & o) != o) continue;
        t[o][m] = static_cast<uint8_t>(t[o][m] | ((m >> child) & 1u) << at);
        ++at;
      }
    }
  }
  return t;
}();
constexpr auto kPatternFrom = [] {
  std::array<std::array<std::array<uint16_t, 8>, 16>, 7> t{};
  for (int o = 1; o < 7; ++o) {
    for (unsigned index = 0; index < 16; ++index) {
      unsigned m = 0;  // the mask with those children
      for (int child = 0, at = 0; child < 8; ++child) {
        if ((child & o) != o) continue;
        m |= ((index >> at) & 1u) << child;
        ++at;
      }
      for (int c = 0; c < 8; ++c) {
        for (int k = 0; k < kPatternLayout.count[c]; ++k) {
          const PatternBit b = kPatternLayout.bits[c][k];
          if (b.o == o && ((m >> b.child) & 1u)) t[o][index][c] = static_cast<uint16_t>(t[o][index][c] | 1u << k);
        }
      }
    }
  }
  return t;
}();

// Version 2's view of a cell beyond its faces, through face links only: a neighbour that no
// existing face neighbour leads to counts as empty (no search). Lookups go through the level's
// sentinel row (index size(): no neighbours, mask 0) rather than branches.
struct Around {
  uint8_t outer = 0;     // bit c: at least 2 of the 3 edge and 1 corner neighbours on octant c's side exist
  uint8_t diagonal = 0;  // bit c: a lower diagonal neighbour of child c outside the cell is set
  // Version 5: per child c, which of its 7 neighbours on c's side exist (bits: the faces x, y, z, the
  // edges xy, xz, yz, the corner), and the pattern bits that the lower cells give it (kPatternFrom).
  std::array<uint8_t, 8> side{};
  std::array<uint16_t, 8> pattern{};
};

template <bool kVersion5>
inline Around Surroundings(const Level& lv, size_t i) {
  const int32_t none = static_cast<int32_t>(lv.size());
  const auto step = [&](int32_t at, int d) { return lv.nbr[at < 0 ? none : at][d]; };
  const auto& f = lv.nbr[i];
  const auto edge = [&](int d1, int d2) {
    const int32_t e = step(f[d1], d2), other = step(f[d2], d1);
    return e >= 0 ? e : other;
  };
  std::array<std::array<int32_t, 2>, 2> xy, xz, yz;  // [side][side], 0 = −, 1 = +
  // Unrolled in full (here and below) so that every index is a constant and the arrays live in
  // registers: as loops they went through the stack, a fifth of the decode.
#pragma GCC unroll 2
  for (int a = 0; a < 2; ++a) {
#pragma GCC unroll 2
    for (int b = 0; b < 2; ++b) {
      xy[a][b] = edge(a, 2 + b);
      xz[a][b] = edge(a, 4 + b);
      yz[a][b] = edge(2 + a, 4 + b);
    }
  }
  // Per neighbour, the children on its side, one bit each (child c = x << 2 | y << 1 | z): the
  // bits of all eight children at once rather than per child.
  const auto on_side = [](int32_t at, unsigned children) { return at >= 0 ? children : 0u; };
  const unsigned along_xy = on_side(xy[0][0], 0x03) | on_side(xy[0][1], 0x0C) | on_side(xy[1][0], 0x30) | on_side(xy[1][1], 0xC0);
  const unsigned along_xz = on_side(xz[0][0], 0x05) | on_side(xz[0][1], 0x0A) | on_side(xz[1][0], 0x50) | on_side(xz[1][1], 0xA0);
  const unsigned along_yz = on_side(yz[0][0], 0x11) | on_side(yz[0][1], 0x22) | on_side(yz[1][0], 0x44) | on_side(yz[1][1], 0x88);
  unsigned corners = 0;
  int32_t lower_corner = -1;
#pragma GCC unroll 8
  for (int c = 0; c < 8; ++c) {
    const int x = (c >> 2) & 1, y = (c >> 1) & 1, z = c & 1;
    bool corner;
    if (kVersion5 || c == 0) {
      const int32_t c1 = step(xy[x][y], 4 + z), c2 = step(xz[x][z], 2 + y), c3 = step(yz[y][z], x);
      corner = (c1 & c2 & c3) >= 0;  // any of the three is >= 0
      if (c == 0) lower_corner = c1 >= 0 ? c1 : c2 >= 0 ? c2 : c3;
    } else {
      // Without version 5's side bits the corner decides `outer` only when exactly one edge exists,
      // and then only the step from that edge can reach it: one lookup instead of three (the
      // same bit: with no edge the step reads the sentinel row, with two `outer` is set already).
      const int32_t via = xy[x][y] >= 0 ? step(xy[x][y], 4 + z) : xz[x][z] >= 0 ? step(xz[x][z], 2 + y) : step(yz[y][z], x);
      corner = via >= 0;
    }
    corners |= corner ? 1u << c : 0u;
  }
  Around out;
  // At least two of the three edges and the corner.
  out.outer = static_cast<uint8_t>((along_xy & (along_xz | along_yz | corners)) | (along_xz & (along_yz | corners)) |
                                   (along_yz & corners));
  if constexpr (kVersion5) {
    const unsigned faces_x = on_side(f[0], 0x0F) | on_side(f[1], 0xF0), faces_y = on_side(f[2], 0x33) | on_side(f[3], 0xCC),
                   faces_z = on_side(f[4], 0x55) | on_side(f[5], 0xAA);
    const uint64_t side = kBitBytes[faces_x] | kBitBytes[faces_y] << 1 | kBitBytes[faces_z] << 2 | kBitBytes[along_xy] << 3 |
                          kBitBytes[along_xz] << 4 | kBitBytes[along_yz] << 5 | kBitBytes[corners] << 6;
#pragma GCC unroll 8
    for (int c = 0; c < 8; ++c) out.side[c] = static_cast<uint8_t>(side >> (8 * c));
  }
  const auto mask = [&](int32_t at) { return lv.mask[at < 0 ? none : at]; };
  out.diagonal = static_cast<uint8_t>(kDiagonalFrom[4][mask(f[0])] | kDiagonalFrom[2][mask(f[2])] |
                                      kDiagonalFrom[1][mask(f[4])] | kDiagonalFrom[6][mask(xy[0][0])] |
                                      kDiagonalFrom[5][mask(xz[0][0])] | kDiagonalFrom[3][mask(yz[0][0])] |
                                      kDiagonalFrom[7][mask(lower_corner)]);
  if constexpr (kVersion5) {
    const std::array<uint8_t, 7> lower = {0, mask(f[4]), mask(f[2]), mask(yz[0][0]), mask(f[0]), mask(xz[0][0]), mask(xy[0][0])};
    // Whole rows OR in, as two words (a row's entry for child c is 0 where o & c != 0).
    std::array<uint64_t, 2> pattern{};
    static_assert(sizeof(pattern) == sizeof(out.pattern));
#pragma GCC unroll 6
    for (int o = 1; o < 7; ++o) {
      std::array<uint64_t, 2> row;
      std::memcpy(row.data(), kPatternFrom[o][kPatternCompact[o][lower[o]]].data(), sizeof(row));
      pattern[0] |= row[0];
      pattern[1] |= row[1];
    }
    std::memcpy(out.pattern.data(), pattern.data(), sizeof(pattern));
  }
  return out;
}

// Version 4's plane memory (G-PCC's planar mode looks at the last coded node on a node's plane the
// same way): per axis and plane of the next level, whether the last coded cell spanning that plane
// had children in it, 0 = none coded yet, 1 = no, 2 = yes. Reaches along whole planes, beyond the
// neighbours: ground and façades (IGN 0.1 m: −5.6 %).
class PlaneMemory {
 public:
  // Forgets all: the planes of `level`'s children, 2^(level+1) per axis. Entries of earlier levels
  // carry an older stamp and read as 0, so nothing is cleared: the buffers come from calloc, whose
  // large blocks are untouched pages, and a level costs the pages its cells touch, not 2^level
  // (a hostile stream of a few bytes may still claim depth 21).
  void Reset(int level) {
    stamp_ = static_cast<uint8_t>(level + 1);  // levels < 32: (stamp << 2 | state) fits a byte
    const size_t n = size_t{2} << level;
    if (n <= size_) return;
    for (auto& axis : last_) {
      axis.reset(static_cast<uint8_t*>(std::calloc(n, 1)));
      if (!axis) throw std::bad_alloc();
    }
    size_ = n;
  }
  // Per child c of a cell at `pos`: 9·x state + 3·y state + z state.
  std::array<uint8_t, 8> States(const std::array<uint32_t, 3>& pos) const {
    const uint8_t* x = &last_[0][2 * pos[0]];
    const uint8_t* y = &last_[1][2 * pos[1]];
    const uint8_t* z = &last_[2][2 * pos[2]];
    std::array<uint8_t, 8> out;
#pragma GCC unroll 8
    for (int c = 0; c < 8; ++c) {
      out[c] = static_cast<uint8_t>(9 * State(x[(c >> 2) & 1]) + 3 * State(y[(c >> 1) & 1]) + State(z[c & 1]));
    }
    return out;
  }
  void Record(const std::array<uint32_t, 3>& pos, unsigned mask) {
    static constexpr std::array<unsigned, 3> kLowHalf = {0x0F, 0x33, 0x55};  // children with the axis bit 0
    const uint8_t no = static_cast<uint8_t>(stamp_ << 2 | 1), yes = static_cast<uint8_t>(stamp_ << 2 | 2);
    for (int axis = 0; axis < 3; ++axis) {
      last_[axis][2 * pos[axis]] = (mask & kLowHalf[axis]) ? yes : no;
      last_[axis][2 * pos[axis] + 1] = (mask & ~kLowHalf[axis] & 0xFFu) ? yes : no;
    }
  }

 private:
  // 0 = none coded yet on this level, 1 = no, 2 = yes.
  unsigned State(uint8_t entry) const { return (entry >> 2) == stamp_ ? entry & 3u : 0u; }

  struct Free {
    void operator()(uint8_t* p) const { std::free(p); }
  };
  std::array<std::unique_ptr<uint8_t[], Free>, 3> last_;
  size_t size_ = 0;
  uint8_t stamp_ = 0;
};

}  // namespace pointdag
