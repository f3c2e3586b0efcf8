#include "pointdag/dag/spatial_coder.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdlib>
#include <new>
#include <memory>

#include "pointdag/dag/mask_mixer.h"
#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

// Classes by height: 1 = voxel masks of brick cells, 2 = brick cell masks, 3.. = internal nodes.
constexpr int kClasses = kMaxDepth + 1;
// Mask bit context: set bits so far (0..3; version 2: 0..1); the known lower neighbours on the
// child's level (3 bits); per axis, whether the parent's neighbour on the child's side exists, else
// whether the one on the other side does (3 states); version 2 adds two bits from the edge and
// corner neighbours (outer, lower_diagonal below). Measured: the child's octant, the full
// 6-neighbour pattern or a count of the known cells around the child dilute the statistics
// (+0.3..3% on lion, autzen, milk); counts of edge neighbours rather than the two thresholds, too.
constexpr int kMaskContexts = 4 * 8 * 27 * 4;

struct SpatialModels {
  std::array<std::array<YoungBitModel, kMaskContexts>, kClasses> mask;
  std::array<BitModel, kClasses> flag;
  std::array<GammaModel, kClasses> ref;
};

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

// Set bits of a byte: the build has no popcount instruction to rely on, and this is the inner loop.
constexpr std::array<uint8_t, 256> kBits = [] {
  std::array<uint8_t, 256> t{};
  for (int i = 0; i < 256; ++i) t[i] = static_cast<uint8_t>(std::popcount(static_cast<unsigned>(i)));
  return t;
}();

int Rank(unsigned mask, int bit) { return kBits[mask & ((1u << bit) - 1)]; }

class EncoderIo {
 public:
  static constexpr bool kEncoding = true;
  template <typename Model>
  int Bit(Model& m, int truth) {
    rc_.Encode(m, truth);
    return truth;
  }
  uint32_t Ref(GammaModel& m, uint32_t truth, uint32_t bound) {
    EncodeGamma(rc_, m, truth + 1, std::bit_width(bound));
    return truth;
  }
  bool failed() const { return false; }
  std::vector<uint8_t> Finish() { return rc_.Finish(); }

 private:
  BinaryRangeEncoder rc_;
};

class DecoderIo {
 public:
  static constexpr bool kEncoding = false;
  explicit DecoderIo(std::span<const uint8_t> payload) : rc_(payload) {}
  template <typename Model>
  int Bit(Model& m, int) { return rc_.Decode(m); }
  uint32_t Ref(GammaModel& m, uint32_t, uint32_t bound) { return DecodeGamma(rc_, m, std::bit_width(bound)) - 1; }
  bool failed() const { return rc_.overrun(); }

 private:
  BinaryRangeDecoder rc_;
};

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

// Version 2's view of a cell beyond its faces, through face links only: a neighbour that no
// existing face neighbour leads to counts as empty (no search). Lookups go through the level's
// sentinel row (index size(): no neighbours, mask 0) rather than branches.
struct Around {
  uint8_t outer = 0;     // bit c: at least 2 of the 3 edge and 1 corner neighbours on octant c's side exist
  uint8_t diagonal = 0;  // bit c: a lower diagonal neighbour of child c outside the cell is set
};

Around Surroundings(const Level& lv, size_t i) {
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
  Around out;
  int32_t lower_corner = -1;
#pragma GCC unroll 8
  for (int c = 0; c < 8; ++c) {
    const int x = (c >> 2) & 1, y = (c >> 1) & 1, z = c & 1;
    const int32_t c1 = step(xy[x][y], 4 + z), c2 = step(xz[x][z], 2 + y), c3 = step(yz[y][z], x);
    const int near = (xy[x][y] >= 0) + (xz[x][z] >= 0) + (yz[y][z] >= 0) + ((c1 & c2 & c3) >= 0);
    out.outer = static_cast<uint8_t>(out.outer | (near >= 2 ? 1u << c : 0u));
    if (c == 0) lower_corner = c1 >= 0 ? c1 : c2 >= 0 ? c2 : c3;
  }
  const auto mask = [&](int32_t at) { return lv.mask[at < 0 ? none : at]; };
  out.diagonal = static_cast<uint8_t>(kDiagonalFrom[4][mask(f[0])] | kDiagonalFrom[2][mask(f[2])] |
                                      kDiagonalFrom[1][mask(f[4])] | kDiagonalFrom[6][mask(xy[0][0])] |
                                      kDiagonalFrom[5][mask(xz[0][0])] | kDiagonalFrom[3][mask(yz[0][0])] |
                                      kDiagonalFrom[7][mask(lower_corner)]);
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

// Codes the 8 child bits of cell i, child 0 first; a last bit that must be 1 (mask non-empty) is
// implied. `edges`: version 2's contexts; `mix`: version 3's mixer (null before); `planes`: the
// plane memory's states per child (version 4).
template <typename Io>
uint8_t CodeMask(Io& io, std::array<YoungBitModel, kMaskContexts>& models, const Level& lv, size_t i, uint8_t truth,
                 bool edges, MaskMixer* mix, const std::array<uint8_t, 8>& planes) {
  unsigned exists = 0;
  uint32_t facing = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const int32_t lo = lv.nbr[i][2 * axis];
    if (lo >= 0) {
      exists |= 1u << axis;
      facing |= kFacing[axis][lv.mask[lo]];
    }
    if (lv.nbr[i][2 * axis + 1] >= 0) exists |= 8u << axis;
  }
  const auto& sides = kSides[exists];
  const Around around = edges ? Surroundings(lv, i) : Around{};
  const unsigned most = edges ? 1 : 3;
  unsigned m = 0;
  unsigned ones = 0;  // set bits so far, at most `most`
#pragma GCC unroll 8  // constant c: its table rows and shifts fold into the code
  for (int c = 0; c < 8; ++c) {
    int bit = 1;
    if (c < 7 || m != 0) {
      const unsigned lower = ((facing >> (4 * c)) & 7u) | kSiblings[c][m];
      unsigned extra = 0;  // outer, then whether any lower diagonal neighbour is set
      if (edges) {
        const bool diagonal = ((around.diagonal >> c) & 1u) || (m & kDiagonalSelf[c]);
        extra = ((around.outer >> c) & 1u) * 2 + (diagonal ? 1u : 0u);
      }
      auto& model = models[((ones * 8 + lower) * 27 + sides[c]) * 4 + extra];
      bit = mix ? mix->Bit(io, model, c, m, lv.parent[i], lower, ones > 0, exists, planes[c], (truth >> c) & 1)
                : io.Bit(model, (truth >> c) & 1);
    }
    m |= static_cast<unsigned>(bit) << c;
    ones += ones < most ? static_cast<unsigned>(bit) : 0u;
  }
  return static_cast<uint8_t>(m);
}

// The next level's cells: the children of the cells expanded here, with their neighbours (and
// with `positions`, their coordinates).
Level Expand(const Level& cur, int level, int levels, const DagArrays& a, bool positions) {
  std::vector<int32_t> base(cur.size(), -1);
  int32_t total = 0;
  for (size_t i = 0; i < cur.size(); ++i) {
    if (level >= levels || cur.first[i]) {
      base[i] = total;
      total += kBits[cur.mask[i]];
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

// One walk for both directions: the encoder's arrays are complete, the decoder's fill as it goes.
// Bricks carry no back-references: every brick slot (a child of a new node of the last internal
// level) is coded in full, `slots` holding its value, and the decoder merges equal bricks.
template <typename Io, typename Arrays>
Status Traverse(Io& io, Arrays& a, int depth, const std::vector<uint64_t>& counts, std::vector<uint64_t>& slots, int version) {
  const int levels = depth - 2;
  const bool edges = version >= 2;
  auto models = std::make_unique<SpatialModels>();
  std::unique_ptr<MaskMixer> mix = version >= 3 ? std::make_unique<MaskMixer>(version >= 4) : nullptr;
  const bool planes = version >= 4;
  PlaneMemory memory;
  std::array<uint8_t, 8> states{};
  const auto known_mask = [&](int level, uint32_t id) -> uint8_t {
    if (level < levels) return a.masks[level][id];
    if (level > levels) return static_cast<uint8_t>(slots[id >> 3] >> (8 * (id & 7)));
    uint8_t cells = 0;
    for (int c = 0; c < 8; ++c) cells = static_cast<uint8_t>(cells | (((slots[id] >> (8 * c)) & 0xFFu) ? 1u << c : 0u));
    return cells;
  };
  constexpr std::array<int32_t, 6> kNone = {-1, -1, -1, -1, -1, -1};
  Level cur;
  cur.Add(0, true, kNone);
  for (int level = 0; level < depth; ++level) {
    const int height = depth - level;
    cur.nbr.push_back(kNone);  // the sentinel row (Surroundings)
    cur.mask.assign(cur.size() + 1, 0);
    cur.kids.assign(cur.size(), 0);
    if (planes) memory.Reset(level);
    uint32_t seen = 0;  // nodes of the next level referenced so far
    size_t child = 0;   // encoder: position in a.children[level]
    for (size_t i = 0; i < cur.size(); ++i) {
      const uint32_t id = cur.id[i];
      if (!cur.first[i]) {
        cur.mask[i] = known_mask(level, id);
        continue;
      }
      if (planes) states = memory.States(cur.pos[i]);
      const uint8_t mask =
          CodeMask(io, models->mask[height], cur, i, Io::kEncoding ? known_mask(level, id) : 0, edges, mix.get(), states);
      cur.mask[i] = mask;
      if (planes) memory.Record(cur.pos[i], mask);
      if constexpr (!Io::kEncoding) {
        if (level < levels) a.masks[level].push_back(mask);
        if (level > levels) slots[id >> 3] |= uint64_t{mask} << (8 * (id & 7));
      }
      if (level >= levels) continue;
      const int n = kBits[mask];
      if (level + 1 == levels) {  // brick slots
        cur.kids[i] = static_cast<uint32_t>(child);
        child += static_cast<size_t>(n);
        if constexpr (!Io::kEncoding) slots.resize(child);
        continue;
      }
      cur.kids[i] = static_cast<uint32_t>(Io::kEncoding ? child : a.children[level].size());
      for (int c = n; c > 0; --c) {
        const uint32_t truth = Io::kEncoding ? a.children[level][child++] : 0;
        uint32_t k;
        if (seen > 0 && io.Bit(models->flag[height], truth < seen ? 1 : 0)) {
          k = io.Ref(models->ref[height], truth, seen);
          if (k >= seen) return Corrupt("geometry stream refers to a node not yet seen");
        } else {
          k = seen++;
          if (seen > counts[level + 1]) return Corrupt("geometry stream holds more nodes than its header declares");
        }
        if constexpr (!Io::kEncoding) a.children[level].push_back(k);
      }
    }
    if (io.failed()) return Truncated("geometry stream ends early");
    if (level + 1 < levels && seen != counts[level + 1]) {
      return Corrupt("geometry stream holds fewer nodes than its header declares");
    }
    if (level + 1 < depth) cur = Expand(cur, level, levels, a, planes);
  }
  return Status::Ok();
}

}  // namespace

StatusOr<std::vector<uint8_t>> EncodeSpatial(const DagArrays& arrays, int depth, int version) {
  EncoderIo io;
  std::vector<uint64_t> counts;
  for (const auto& m : arrays.masks) counts.push_back(m.size());
  counts.push_back(arrays.leaves.size());
  std::vector<uint64_t> slots;
  if (arrays.masks.empty()) {
    slots = arrays.leaves;
  } else {
    for (uint32_t k : arrays.children.back()) slots.push_back(arrays.leaves[k]);
  }
  RETURN_IF_ERROR(Traverse(io, arrays, depth, counts, slots, version));
  return io.Finish();
}

StatusOr<DagArrays> DecodeSpatial(std::span<const uint8_t> payload, int depth, const std::vector<uint64_t>& counts,
                                  int version) {
  const int levels = depth - 2;
  DagArrays a;
  a.masks.resize(levels);
  a.children.resize(levels);
  for (int level = 0; level < levels; ++level) a.masks[level].reserve(counts[level]);
  std::vector<uint64_t> slots(levels == 0 ? 1 : 0);
  DecoderIo io(payload);
  RETURN_IF_ERROR(Traverse(io, a, depth, counts, slots, version));
  // Equal bricks become one, numbered in the order first seen: the canonical order. An open-addressed
  // table of leaf ordinals (at most half full: sized by the bricks decoded, never above the header's
  // count) rather than a node-based map.
  const int bits = static_cast<int>(std::bit_width(std::min<uint64_t>(counts[levels], slots.size()))) + 1;
  std::vector<uint32_t> table(size_t{1} << bits, UINT32_MAX);
  a.leaves.reserve(counts[levels]);
  std::vector<uint32_t> ids;
  ids.reserve(slots.size());
  for (uint64_t brick : slots) {
    size_t at = static_cast<size_t>(((brick ^ (brick >> 29)) * 0x9E3779B97F4A7C15ull) >> (64 - bits));
    while (table[at] != UINT32_MAX && a.leaves[table[at]] != brick) at = (at + 1) & (table.size() - 1);
    if (table[at] == UINT32_MAX) {
      if (a.leaves.size() == counts[levels]) return Corrupt("geometry stream holds more bricks than its header declares");
      table[at] = static_cast<uint32_t>(a.leaves.size());
      a.leaves.push_back(brick);
    }
    ids.push_back(table[at]);
  }
  if (a.leaves.size() != counts[levels]) return Corrupt("geometry stream holds fewer bricks than its header declares");
  if (levels > 0) a.children.back() = std::move(ids);
  return a;
}

}  // namespace pointdag
