#include "pointdag/dag/spatial_coder.h"

#include <algorithm>
#include <array>
#include <bit>
#include <memory>
#include <string>

#include "pointdag/dag/mask_mixer.h"
#include "pointdag/dag/mask_mixer5.h"
#include "pointdag/dag/slot_merge.h"
#include "pointdag/dag/spatial_context.h"
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
  explicit SpatialModels(int depth) : mask(static_cast<size_t>(depth) + 1) {}
  // By height, only those a walk of `depth` visits (1..depth): all 21 were 456 kB to initialise
  // per tile, more than a tile's geometry decode touches.
  std::vector<std::array<YoungBitModel, kMaskContexts>> mask;
  std::array<BitModel, kClasses> flag;
  std::array<YoungBitModel, kClasses> young_flag;  // version 8's flags
  std::array<GammaModel, kClasses> ref;
};

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
  std::vector<uint8_t> Finish(bool compact) { return compact ? rc_.FinishCompact() : rc_.Finish(); }

 private:
  BinaryRangeEncoder rc_;
};

class DecoderIo {
 public:
  static constexpr bool kEncoding = false;
  DecoderIo(std::span<const uint8_t> payload, bool compact) : rc_(payload, compact) {}
  template <typename Model>
  int Bit(Model& m, int) { return rc_.Decode(m); }
  uint32_t Ref(GammaModel& m, uint32_t, uint32_t bound) { return DecodeGamma(rc_, m, std::bit_width(bound)) - 1; }
  bool failed() const { return rc_.overrun(); }

 private:
  BinaryRangeDecoder rc_;
};

// Bit c: byte c of v (a brick's cell c) is non-zero. Each byte's bit 7 says so, and the multiply
// gathers those eight bits into the top byte (no two products meet, so nothing carries).
uint8_t NonZeroBytes(uint64_t v) {
  constexpr uint64_t kLow7 = 0x7F7F7F7F7F7F7F7Full;
  const uint64_t high = (((v & kLow7) + kLow7) | v) & ~kLow7;
  return static_cast<uint8_t>(((high >> 7) * 0x0102040810204080ull) >> 56);
}

// The mixers a stream's version uses: none (1, 2), version 3's and 4's, version 5's.
struct Mixers {
  std::unique_ptr<MaskMixer> v3;
  std::unique_ptr<MaskMixer5> v5;
};

// Codes the 8 child bits of cell i, child 0 first; a last bit that must be 1 (mask non-empty) is
// implied. `edges`: version 2's contexts; `mix`: the version's mixer; `planes`: the plane memory's
// states per child (version 4 on); `group`: the class group (version 5).
template <bool kVersion5, typename Io>
uint8_t CodeMask(Io& io, std::array<YoungBitModel, kMaskContexts>& models, const Level& lv, size_t i, uint8_t truth,
                 bool edges, const Mixers& mix, const std::array<uint8_t, 8>& planes, unsigned group) {
  if constexpr (kVersion5) edges = true;  // version 2's contexts, as a constant: their branches fold
  unsigned exists = 0;
  uint32_t facing = 0;
  std::array<unsigned, 3> below{};  // the masks of the lower face neighbours (0: none)
  // Unrolled and without branches (a missing neighbour reads the sentinel mask 0, whose facing
  // bits are 0): which neighbours exist is a coin toss to the branch predictor.
  const int32_t none = static_cast<int32_t>(lv.size());
#pragma GCC unroll 3
  for (int axis = 0; axis < 3; ++axis) {
    const int32_t lo = lv.nbr[i][2 * axis];
    exists |= (lo >= 0 ? 1u : 0u) << axis | (lv.nbr[i][2 * axis + 1] >= 0 ? 8u : 0u) << axis;
    below[axis] = lv.mask[lo >= 0 ? lo : none];
    facing |= kFacing[axis][below[axis]];
  }
  const auto& sides = kSides[exists];
  // Version 5: child c's three neighbours at −2 (bit c of the lower masks) in byte c.
  const uint64_t lower2s = kVersion5 ? kBitBytes[below[0]] | kBitBytes[below[1]] << 1 | kBitBytes[below[2]] << 2 : 0;
  const Around around = edges ? Surroundings<kVersion5>(lv, i) : Around{};
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
      if constexpr (kVersion5) {
        const unsigned lower2 = (lower2s >> (8 * c)) & 7u;
        const unsigned pattern = around.pattern[c] | kPatternSelf[c][m] | lower2 << kPatternLayout.count[c];
        const unsigned apm = (((c * 8 + lower) * 8 + lower2) * 4) + extra;
        bit = mix.v5->Bit(io, model, c, m, ones > 0, exists, planes[c], kPatternBase[group][c] + pattern, around.side[c], apm,
                          (truth >> c) & 1);
      } else {
        bit = mix.v3 ? mix.v3->Bit(io, model, c, m, lv.parent[i], lower, ones > 0, exists, planes[c], (truth >> c) & 1)
                     : io.Bit(model, (truth >> c) & 1);
      }
    }
    m |= static_cast<unsigned>(bit) << c;
    ones += ones < most ? static_cast<unsigned>(bit) : 0u;
  }
  return static_cast<uint8_t>(m);
}

// One walk for both directions: the encoder's arrays are complete, the decoder's fill as it goes.
// Slots carry no back-references: every child of a first cell on the level above the slot level
// (slot_merge.h) is coded in full, the encoder walking arrays in which the slot levels are a tree,
// and the decoder merges equal nodes; `slots` holds the bricks' values. `counts`: the level table
// the decoder checks (none in version 8, nor for the encoder), else `max_nodes` bounds the nodes
// of the levels above the slots.
template <typename Io, typename Arrays>
Status Traverse(Io& io, Arrays& a, int depth, const std::vector<uint64_t>* counts, uint64_t max_nodes, std::vector<uint64_t>& slots,
                int version) {
  const int levels = depth - 2;
  const int slot_level = SlotLevel(levels, version);
  const bool edges = version >= 2;
  auto models = std::make_unique<SpatialModels>(depth);
  Mixers mix;
  if (version >= 5) {
    mix.v5 = std::make_unique<MaskMixer5>(version);
  } else if (version >= 3) {
    mix.v3 = std::make_unique<MaskMixer>(version >= 4);
  }
  const bool planes = version >= 4;
  const bool young_flags = version >= 8;
  uint64_t nodes = 1;  // on the levels above the slots, the root included
  PlaneMemory memory;
  std::array<uint8_t, 8> states{};
  const auto known_mask = [&](int level, uint32_t id) -> uint8_t {
    if (level < levels) return a.masks[level][id];
    if (level > levels) return static_cast<uint8_t>(slots[id >> 3] >> (8 * (id & 7)));
    return NonZeroBytes(slots[id]);
  };
  constexpr std::array<int32_t, 6> kNone = {-1, -1, -1, -1, -1, -1};
  Level cur;
  cur.Add(0, true, kNone);
  for (int level = 0; level < depth; ++level) {
    const int height = depth - level;
    const unsigned group = ClassGroup(height);
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
      const uint8_t known = Io::kEncoding ? known_mask(level, id) : 0;
      const uint8_t mask = mix.v5 ? CodeMask<true>(io, models->mask[height], cur, i, known, edges, mix, states, group)
                                  : CodeMask<false>(io, models->mask[height], cur, i, known, edges, mix, states, group);
      cur.mask[i] = mask;
      if (planes) memory.Record(cur.pos[i], mask);
      if constexpr (!Io::kEncoding) {
        if (level < levels) a.masks[level].push_back(mask);
        if (level > levels) slots[id >> 3] |= uint64_t{mask} << (8 * (id & 7));
      }
      if (level >= levels) continue;
      const int n = kByteBits[mask];
      if (level + 1 == levels) {  // brick slots
        cur.kids[i] = static_cast<uint32_t>(child);
        child += static_cast<size_t>(n);
        if constexpr (!Io::kEncoding) slots.resize(child);
        continue;
      }
      cur.kids[i] = static_cast<uint32_t>(Io::kEncoding ? child : a.children[level].size());
      if (level + 1 >= slot_level) {  // slots of an internal level: new nodes, numbered in order
        if constexpr (!Io::kEncoding) {
          for (int c = 0; c < n; ++c) a.children[level].push_back(seen++);
        }
        child += static_cast<size_t>(n);
        continue;
      }
      for (int c = n; c > 0; --c) {
        const uint32_t truth = Io::kEncoding ? a.children[level][child++] : 0;
        uint32_t k;
        const int back = truth < seen ? 1 : 0;
        if (seen > 0 && (young_flags ? io.Bit(models->young_flag[height], back) : io.Bit(models->flag[height], back))) {
          k = io.Ref(models->ref[height], truth, seen);
          if (k >= seen) return Corrupt("geometry stream refers to a node not yet seen");
        } else {
          k = seen++;
          if (counts && seen > (*counts)[level + 1]) return Corrupt("geometry stream holds more nodes than its header declares");
          if (++nodes > max_nodes) return Corrupt("geometry stream holds more nodes than its voxels allow");
        }
        if constexpr (!Io::kEncoding) a.children[level].push_back(k);
      }
    }
    if (io.failed()) return Truncated("geometry stream ends early");
    if (counts && level + 1 < slot_level && seen != (*counts)[level + 1]) {
      return Corrupt("geometry stream holds fewer nodes than its header declares");
    }
    if (level + 1 < depth) cur = Expand(cur, level, levels, a, planes);
  }
  return Status::Ok();
}

}  // namespace

StatusOr<std::vector<uint8_t>> EncodeSpatial(const DagArrays& arrays, int depth, int version) {
  EncoderIo io;
  constexpr uint64_t kUnbounded = UINT64_MAX;
  std::vector<uint64_t> slots;
  if (arrays.masks.empty()) {
    slots = arrays.leaves;
  } else {
    for (uint32_t k : arrays.children.back()) slots.push_back(arrays.leaves[k]);
  }
  const int slot_level = SlotLevel(depth - 2, version);
  if (slot_level < depth - 2) {
    if (!SlotsStoredOnce(arrays, slot_level)) {
      return InvalidArgument("geometry coder 2 version 5 needs each node of heights 3 and 4 stored once: one repeats");
    }
    const DagArrays tree = ExpandSlots(arrays, slot_level);
    slots.clear();
    for (uint32_t k : tree.children.back()) slots.push_back(tree.leaves[k]);
    RETURN_IF_ERROR(Traverse(io, tree, depth, nullptr, kUnbounded, slots, version));
  } else {
    RETURN_IF_ERROR(Traverse(io, arrays, depth, nullptr, kUnbounded, slots, version));
  }
  return io.Finish(version >= kCompactSpatialVersion);
}

StatusOr<DagArrays> DecodeSpatial(std::span<const uint8_t> payload, int depth, const std::vector<uint64_t>* counts,
                                  uint64_t max_nodes, int version) {
  const int levels = depth - 2;
  DagArrays a;
  a.masks.resize(levels);
  a.children.resize(levels);
  if (counts) {
    for (int level = 0; level < levels; ++level) a.masks[level].reserve((*counts)[level]);
  }
  std::vector<uint64_t> slots(levels == 0 ? 1 : 0);
  DecoderIo io(payload, version >= kCompactSpatialVersion);
  RETURN_IF_ERROR(Traverse(io, a, depth, counts, max_nodes, slots, version));
  RETURN_IF_ERROR(MergeSlots(a, slots, counts, SlotLevel(levels, version)));
  uint64_t total = a.leaves.size();
  for (const auto& masks : a.masks) total += masks.size();
  if (total > max_nodes) return Corrupt("geometry stream holds more nodes than its voxels allow");
  return a;
}

StatusOr<std::vector<uint8_t>> EncodeCompactSpatial(const DagArrays& arrays, int depth, CountMode mode) {
  ASSIGN_OR_RETURN(std::vector<uint8_t> payload, EncodeSpatial(arrays, depth, kCompactSpatialVersion));
  payload.insert(payload.begin(), {static_cast<uint8_t>(kCompactSpatialVersion),
                                   static_cast<uint8_t>(depth | static_cast<int>(mode) << 5)});
  return payload;
}

StatusOr<Svdag> DecodeCompactSpatial(std::span<const uint8_t> bytes, uint64_t max_nodes) {
  if (bytes.size() < 2) return Truncated("geometry stream is shorter than its 2-byte header");
  const int depth = bytes[1] & 31;
  if (depth < 2 || depth > kMaxDepth) return Corrupt("geometry stream depth " + std::to_string(depth) + " is outside 2..21");
  if (bytes[1] >> 6 != 0) return Corrupt("geometry stream sets reserved header bits");
  const auto mode = static_cast<CountMode>(bytes[1] >> 5);
  ASSIGN_OR_RETURN(const DagArrays arrays, DecodeSpatial(bytes.subspan(2), depth, nullptr, max_nodes, kCompactSpatialVersion));
  ASSIGN_OR_RETURN(Svdag dag, FromArrays(arrays, depth, mode));
  RETURN_IF_ERROR(dag.Validate());
  return dag;
}

}  // namespace pointdag
