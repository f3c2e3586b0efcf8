// The neighbourhood the hierarchical colors (hierarchical_colors.cc) predict a node's children from:
// its 18 face and edge neighbours, which of them each child slot reads and with what weight, and
// which cells a node must look up (proto/PDAG_FORMAT.md §3, "Neighbours").
#pragma once

#include <array>
#include <cstdint>

namespace pointdag::hierarchical {

// A node's 18 face and edge neighbours, as steps of −1/0/+1 along Morton bit positions 0, 1, 2.
struct Offset {
  std::array<int8_t, 3> d;
  int nonzero;
};
constexpr int OffsetIndex(int d0, int d1, int d2) { return (d0 + 1) + 3 * (d1 + 1) + 9 * (d2 + 1); }
constexpr auto kOffsets = [] {
  std::array<Offset, 18> t{};
  int n = 0;
  for (int d2 = -1; d2 <= 1; ++d2) {
    for (int d1 = -1; d1 <= 1; ++d1) {
      for (int d0 = -1; d0 <= 1; ++d0) {
        const int nonzero = (d0 != 0) + (d1 != 0) + (d2 != 0);
        if (nonzero == 1 || nonzero == 2) {
          t[n++] = {{static_cast<int8_t>(d0), static_cast<int8_t>(d1), static_cast<int8_t>(d2)}, nonzero};
        }
      }
    }
  }
  return t;
}();

// Prediction weights: the parent 8; the parent's face (2) and edge (1) neighbours on the child's
// side; the child's own face (2) and edge (1) neighbours already decoded (in earlier parents).
constexpr int64_t kParentWeight = 8;

// A predictor of the child in slot s: the parent-level cell `up` (index into the 27 around the
// parent), at the children's level its child in `slot`, and the weight.
struct Predictor {
  uint8_t up, slot;
  int8_t weight;
};
// Per slot: the parent's 6 neighbours on the child's side (3 faces, 3 edges).
constexpr auto kParentSide = [] {
  std::array<std::array<Predictor, 6>, 8> t{};
  for (int s = 0; s < 8; ++s) {
    int n = 0;
    for (const Offset& o : kOffsets) {
      bool toward = true;
      for (int a = 0; a < 3; ++a) toward = toward && (o.d[a] == 0 || o.d[a] == (((s >> a) & 1) ? 1 : -1));
      if (toward) t[s][n++] = {static_cast<uint8_t>(OffsetIndex(o.d[0], o.d[1], o.d[2])), 0, static_cast<int8_t>(o.nonzero == 1 ? 2 : 1)};
    }
  }
  return t;
}();
// Per slot: the child's 12 face and edge neighbours outside its parent (the 6 inside are siblings,
// decoded with it).
constexpr auto kChildSide = [] {
  std::array<std::array<Predictor, 12>, 8> t{};
  for (int s = 0; s < 8; ++s) {
    int n = 0;
    for (const Offset& o : kOffsets) {
      std::array<int, 3> inner{}, up{};
      for (int a = 0; a < 3; ++a) {
        const int v = ((s >> a) & 1) + o.d[a];
        up[a] = v < 0 ? -1 : (v > 1 ? 1 : 0);
        inner[a] = v & 1;
      }
      if (up[0] == 0 && up[1] == 0 && up[2] == 0) continue;
      t[s][n++] = {static_cast<uint8_t>(OffsetIndex(up[0], up[1], up[2])), static_cast<uint8_t>(inner[0] | inner[1] << 1 | inner[2] << 2),
                   static_cast<int8_t>(o.nonzero == 1 ? 2 : 1)};
    }
  }
  return t;
}();

// Which of the 27 cells around a node a child in slot s reads (bit OffsetIndex): its parent side at
// any position in the level's order, and (with the face neighbours' nonzero counts) cells that must
// come before the node: the only ones looked up.
constexpr auto kParentSideCells = [] {
  std::array<uint32_t, 8> t{};
  for (int s = 0; s < 8; ++s) {
    for (const Predictor& p : kParentSide[s]) t[s] |= 1u << p.up;
  }
  return t;
}();
constexpr auto kEarlierCells = [] {
  std::array<uint32_t, 8> t{};
  for (int s = 0; s < 8; ++s) {
    for (const Predictor& p : kChildSide[s]) t[s] |= 1u << p.up;
    for (const Offset& o : kOffsets) {
      if (o.nonzero == 1) t[s] |= 1u << OffsetIndex(o.d[0], o.d[1], o.d[2]);
    }
  }
  return t;
}();

}  // namespace pointdag::hierarchical
