#include "pointdag/color/weight_context.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

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

// A neighbour that may precede a voxel, seen from the voxel's cell in its brick: the brick it lies
// in (its slot in a brick's Near), its bit there, and its weight.
struct Neighbour {
  uint8_t slot, bit, weight;
};

// Per cell of a brick (its bit), the cells at the offsets up to `reach` on each axis (and beyond
// `inside` on one) that may precede it: those with a negative component, as the code grows with
// each coordinate; those later in its own brick are left out (weight 0). Offsets of -2..2 stay
// within the bricks around the cell's own.
template <int kCount, typename Weight>
constexpr auto MakeNeighbourTable(int inside, int reach, Weight weight) {
  std::array<std::array<Neighbour, kCount>, 64> table{};
  for (int own = 0; own < 64; ++own) {
    const int lx = (own >> 2 & 1) | (own >> 4 & 2), ly = (own >> 1 & 1) | (own >> 3 & 2), lz = (own & 1) | (own >> 2 & 2);
    int n = 0;
    for (int dx = -reach; dx <= reach; ++dx) {
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dz = -reach; dz <= reach; ++dz) {
          if ((dx >= 0 && dy >= 0 && dz >= 0) || std::max({dx, -dx, dy, -dy, dz, -dz}) <= inside) continue;
          const int nx = lx + dx, ny = ly + dy, nz = lz + dz;
          const int slot = ((nx >> 2) + 1) * 9 + ((ny >> 2) + 1) * 3 + ((nz >> 2) + 1);  // >> 2: -1, 0 or 1
          const int bit = BrickBit(nx & 3, ny & 3, nz & 3);
          const bool later = slot == 13 && bit > own;
          table[own][n++] = {static_cast<uint8_t>(slot), static_cast<uint8_t>(bit), static_cast<uint8_t>(later ? 0 : weight(dx, dy, dz))};
        }
      }
    }
  }
  return table;
}
// The same neighbours grouped by the brick they lie in and their weight, one mask of cells per
// group: a voxel visits the neighbours present (a group's mask ANDed with its brick's cells)
// instead of testing each of them in turn (lion 1 cm, 38 dB encode: Position 205 M -> 179 M
// instructions).
struct NeighbourGroup {
  uint64_t cells = 0;
  uint8_t slot = 0, weight = 0;
};
// At most 2 bricks an axis (8 slots) times 3 weights.
constexpr size_t kMaxGroups = 24;
struct CellGroups {
  std::array<NeighbourGroup, kMaxGroups> group{};
  size_t count = 0;
};
template <size_t kCount>
constexpr auto GroupNeighbours(const std::array<std::array<Neighbour, kCount>, 64>& table) {
  std::array<CellGroups, 64> groups{};
  for (size_t own = 0; own < 64; ++own) {
    CellGroups& cell = groups[own];
    for (const Neighbour& n : table[own]) {
      if (n.weight == 0) continue;
      size_t g = 0;
      while (g < cell.count && (cell.group[g].slot != n.slot || cell.group[g].weight != n.weight)) ++g;
      if (g == cell.count) cell.group[cell.count++] = {0, n.slot, n.weight};
      cell.group[g].cells |= uint64_t{1} << n.bit;
    }
  }
  return groups;
}

// The 19 of the 26 face, edge and corner neighbours that may precede: faces weigh 4, edges 2, corners 1.
constexpr auto kNeighbours = GroupNeighbours(
    MakeNeighbourTable<19>(0, 1, [](int dx, int dy, int dz) { return 8 >> ((dx != 0) + (dy != 0) + (dz != 0)); }));
// The 79 of the 98 cells two away (the 5x5x5 shell) that may precede, weighted by squared distance
// d² 4 -> 3, 5 or 6 -> 2, 8, 9 or 12 -> 1 (the lossless coder's wide weights there).
constexpr auto kFarNeighbours = GroupNeighbours(MakeNeighbourTable<79>(1, 2, [](int dx, int dy, int dz) {
  const int d2 = dx * dx + dy * dy + dz * dz;
  return d2 == 4 ? 3 : d2 <= 6 ? 2 : 1;
}));

}  // namespace

WeightContexts::WeightContexts(std::span<const uint64_t> morton)
    : morton_(morton), decoded_(morton.size()), bricks_(morton),
      entered_(std::min<size_t>(128, std::bit_ceil(std::max<size_t>(1, bricks_.all().size())))),
      entered_mask_(entered_.size() - 1) {}

const WeightContexts::Near& WeightContexts::Seek(size_t& cursor, uint64_t i) {
  size_t k = cursor;
  const std::vector<VoxelBrick>& bricks = bricks_.all();
  while (k + 1 < bricks.size() && bricks[k + 1].first <= i) ++k;
  cursor = k;
  Entered& entry = entered_[k & entered_mask_];
  if (entry.brick != k) EnterBrick(entry, k);
  return entry.near;
}

void WeightContexts::EnterBrick(Entered& entry, size_t k) {
  entry.brick = k;
  const uint64_t code = bricks_.all()[k].code;
  // Each axis' bits moved by -1, 0, +1 once: a neighbour's code is one of each axis' ORed together.
  std::array<std::array<uint64_t, 3>, 3> moved{};
  std::array<std::array<bool, 3>, 3> inside{};
  for (int axis = 0; axis < 3; ++axis) {
    for (int d = -1; d <= 1; ++d) {
      uint64_t out = 0;
      inside[axis][d + 1] = Moved(code, axis, d, out);
      moved[axis][d + 1] = out & kAxisBits[axis];
    }
  }
  const uint64_t rest = code & ~(kAxisBits[0] | kAxisBits[1] | kAxisBits[2]);
  for (int x = 0; x < 3; ++x) {
    for (int y = 0; y < 3; ++y) {
      for (int z = 0; z < 3; ++z) {
        VoxelBrick& near = entry.near[x * 9 + y * 3 + z];
        near = {0, 0, 0};
        if (!inside[0][x] || !inside[1][y] || !inside[2][z]) continue;  // outside the grid
        const uint64_t c = moved[0][x] | moved[1][y] | moved[2][z] | rest;
        if (c > code) continue;  // after this brick
        if (const VoxelBrick* found = bricks_.Find(c)) near = *found;
      }
    }
  }
}

template <bool kBelowOnly, typename Table>
uint64_t WeightContexts::PrecedingSum(const Table& table, const Near& near_bricks, uint64_t i, uint64_t below) const {
  const auto& cell = table[morton_[i] & 63];
  uint64_t sum = 0;
  for (size_t g = 0; g < cell.count; ++g) {
    const NeighbourGroup& group = cell.group[g];
    const VoxelBrick& near = near_bricks[group.slot];
    uint64_t colors = 0;  // the group's, weighed once
    for (uint64_t present = near.cells & group.cells; present != 0; present &= present - 1) {
      const uint32_t j = near.IndexOf(std::countr_zero(present));
      if (!kBelowOnly || j < below) colors += decoded_[j];
    }
    sum += group.weight * colors;
  }
  return sum;
}

NeighbourPosition WeightContexts::Position(uint64_t i, const Endpoints& ends, int bits, bool far) {
  const Near& near = Seek(weights_, i);
  uint64_t sum = PrecedingSum<false>(kNeighbours, near, i, i);  // the neighbours' colors, weighted
  const bool beyond = sum == 0 && far;
  if (beyond) sum = PrecedingSum<false>(kFarNeighbours, near, i, i);
  const int64_t total = static_cast<int64_t>(sum >> 48), r = sum & 0xFFFF, g = sum >> 16 & 0xFFFF, b = sum >> 32 & 0xFFFF;
  if (total == 0) return {};
  // Their mean's position on the segment A -> B in weight (half) steps, rounded, clamped to 0..m
  // (0..2m; 0 where A = B): one division per weight, not one per neighbour.
  const int64_t m = (1 << bits) - 1;
  const int64_t sr = ends.b.r - ends.a.r, sg = ends.b.g - ends.a.g, sb = ends.b.b - ends.a.b;
  const int64_t len2 = sr * sr + sg * sg + sb * sb;
  const int64_t dot = (r - total * ends.a.r) * sr + (g - total * ends.a.g) * sg + (b - total * ends.a.b) * sb;
  if (dot <= 0 || len2 == 0) return {true, beyond, 0, 0};
  // In 32 bits, whose division is the cheaper: dot and len2 are at most total x 3 x 255^2 and 3 x
  // 255^2 (each neighbour's (c - A).(B - A) by Cauchy-Schwarz), total at most 124, so 4 dot m +
  // total len2 <= 61 x 124 x 195075 < 2^31.
  const auto unit = static_cast<uint32_t>(2 * total * len2), half = static_cast<uint32_t>(total * len2);
  const auto scaled = static_cast<uint32_t>(dot * m);
  return {true, beyond, std::min(static_cast<uint32_t>(m), (2 * scaled + half) / unit),
          std::min(static_cast<uint32_t>(2 * m), (4 * scaled + half) / unit)};
}

BlockSurroundings WeightContexts::Surroundings(uint64_t start, uint32_t length) {
  BlockSurroundings s;
  const uint64_t stop = start + std::min(length, kPredictingVoxels);
  for (uint64_t i = start; i < stop; ++i) {
    const uint64_t sum = PrecedingSum<true>(kNeighbours, Seek(ends_, i), i, start);  // inside the block: not decoded yet
    s.r += sum & 0xFFFF;
    s.g += sum >> 16 & 0xFFFF;
    s.b += sum >> 32 & 0xFFFF;
    s.weight += sum >> 48;
  }
  return s;
}

}  // namespace pointdag
