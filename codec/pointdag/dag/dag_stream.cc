#include "pointdag/dag/dag_stream.h"

#include <zstd.h>

#include <array>
#include <bit>
#include <memory>
#include <string>
#include <type_traits>
#include <unordered_set>

#include "pointdag/dag/dag_arrays.h"
#include "pointdag/dag/spatial_coder.h"
#include "pointdag/dag/table_coder.h"
#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/entropy/varint.h"
#include "pointdag/entropy/zstd_stream.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

constexpr int kZstdLevel = 19;

// Mask contexts: internal nodes by height (3..21), brick cell masks, brick voxel masks. Measured:
// conditioning further on the octant in the parent and the parent's occupancy around it, or on the
// cell of a brick, dilutes the statistics and costs 1-10% on every scan in ../shared/data.
constexpr int kVoxelClass = 1;
constexpr int kBrickCellClass = 2;
constexpr int kMaskClasses = kMaxDepth + 1;
// A coded bit costs at least -log2(1 - 4/4096) = 0.0014 bits (12-bit probabilities of at most
// 4091/4096, plus the coder's rounding) and a node at least one 8-bit mask: 8 / (8 x 0.0014) < 720.
constexpr uint64_t kMaxContextNodesPerByte = 720;

// ---- Symbol sinks and sources: the traversal is written once per direction, the coding twice. ----

class ZstdSink {
 public:
  void Mask(int, uint8_t m) { masks_.push_back(m); }
  void Flag(int, bool back) {
    if (flag_bits_ % 8 == 0) flags_.push_back(0);
    if (back) flags_.back() = static_cast<uint8_t>(flags_.back() | (1u << (flag_bits_ % 8)));
    ++flag_bits_;
  }
  void Ref(int, uint32_t ordinal, uint32_t) { PutVarint(refs_, ordinal); }

  StatusOr<std::vector<uint8_t>> Finish(std::vector<uint8_t> out) {
    std::array<std::vector<uint8_t>*, 3> streams = {&masks_, &flags_, &refs_};
    std::vector<std::vector<uint8_t>> packed;
    for (auto* s : streams) {
      std::vector<uint8_t> z(ZSTD_compressBound(s->size()));
      const size_t n = ZSTD_compress(z.data(), z.size(), s->data(), s->size(), kZstdLevel);
      if (ZSTD_isError(n)) return Internal(std::string("zstd: ") + ZSTD_getErrorName(n));
      z.resize(n);
      PutVarint(out, n);
      packed.push_back(std::move(z));
    }
    for (auto& z : packed) out.insert(out.end(), z.begin(), z.end());
    return out;
  }

 private:
  std::vector<uint8_t> masks_, flags_, refs_;
  uint64_t flag_bits_ = 0;
};

class ZstdSource {
 public:
  // Decompresses the three streams that follow `pos`. The masks may hold what `counts` can need:
  // one per node, a brick's cell mask plus up to 8 voxel masks. The internal nodes' masks then say
  // how many children there are: a flag bit each, a varint of at most 5 bytes per reference.
  Status Open(std::span<const uint8_t> bytes, size_t pos, const std::vector<uint64_t>& counts) {
    uint64_t lengths[3];
    for (auto& len : lengths) {
      if (!GetVarint(bytes, pos, len)) return Truncated("geometry stream ends inside its length table");
    }
    uint64_t internal = 0;
    for (size_t level = 0; level + 1 < counts.size(); ++level) internal += counts[level];
    const auto frame = [&](int i) -> StatusOr<std::span<const uint8_t>> {
      if (lengths[i] > bytes.size() - pos) return Truncated("geometry stream is shorter than its length table says");
      const auto out = bytes.subspan(pos, lengths[i]);
      pos += lengths[i];
      return out;
    };
    ASSIGN_OR_RETURN(const auto masks, frame(0));
    RETURN_IF_ERROR(DecompressBounded(masks, internal + 9 * counts.back(), masks_, "geometry mask stream"));
    uint64_t children = 0;
    for (size_t i = 0; i < std::min<uint64_t>(internal, masks_.size()); ++i) children += std::popcount(masks_[i]);
    ASSIGN_OR_RETURN(const auto flags, frame(1));
    RETURN_IF_ERROR(DecompressBounded(flags, children / 8 + 1, flags_, "geometry flag stream"));
    ASSIGN_OR_RETURN(const auto refs, frame(2));
    return DecompressBounded(refs, 5 * children, refs_, "geometry reference stream");
  }
  uint8_t Mask(int) { return mask_pos_ < masks_.size() ? masks_[mask_pos_++] : Fail(); }
  bool Flag(int) {
    if (flag_bit_ / 8 >= flags_.size()) return Fail();
    const bool back = (flags_[flag_bit_ / 8] >> (flag_bit_ % 8)) & 1u;
    ++flag_bit_;
    return back;
  }
  uint32_t Ref(int, uint32_t) {
    uint64_t v = 0;
    if (!GetVarint(refs_, ref_pos_, v) || v > 0xFFFFFFFFu) return Fail();
    return static_cast<uint32_t>(v);
  }
  bool failed() const { return failed_; }

 private:
  uint8_t Fail() {
    failed_ = true;
    return 0;
  }
  std::vector<uint8_t> masks_, flags_, refs_;
  size_t mask_pos_ = 0, ref_pos_ = 0;
  uint64_t flag_bit_ = 0;
  bool failed_ = false;
};

// Probability models shared by the context encoder and decoder. Back-references are skewed towards
// nodes seen early (a handful of bricks repeat everywhere), hence a gamma code per height.
struct ContextModels {
  std::array<BitTreeModel<8>, kMaskClasses> mask;
  std::array<BitModel, kMaskClasses> flag;
  std::array<GammaModel, kMaskClasses> ref;
};

class ContextSink {
 public:
  void Mask(int cls, uint8_t m) { EncodeBitTree<8>(rc_, models_.mask[cls], m); }
  void Flag(int cls, bool back) { rc_.Encode(models_.flag[cls], back ? 1 : 0); }
  void Ref(int cls, uint32_t ordinal, uint32_t bound) {
    EncodeGamma(rc_, models_.ref[cls], ordinal + 1, std::bit_width(bound));
  }
  StatusOr<std::vector<uint8_t>> Finish(std::vector<uint8_t> out) {
    const std::vector<uint8_t> payload = rc_.Finish();
    out.insert(out.end(), payload.begin(), payload.end());
    return out;
  }

 private:
  ContextModels models_;
  BinaryRangeEncoder rc_;
};

class ContextSource {
 public:
  explicit ContextSource(std::span<const uint8_t> payload) : rc_(payload) {}
  uint8_t Mask(int cls) { return static_cast<uint8_t>(DecodeBitTree<8>(rc_, models_.mask[cls])); }
  bool Flag(int cls) { return rc_.Decode(models_.flag[cls]) != 0; }
  uint32_t Ref(int cls, uint32_t bound) { return DecodeGamma(rc_, models_.ref[cls], std::bit_width(bound)) - 1; }
  bool failed() const { return rc_.overrun(); }

 private:
  ContextModels models_;
  BinaryRangeDecoder rc_;
};

// ---- Traversals: the symbols of §2.2 in stream order ----

template <typename Sink>
void WriteSymbols(const DagArrays& a, Sink& sink, int depth) {
  const int levels = static_cast<int>(a.masks.size());
  for (int level = 0; level < levels; ++level) {
    const int cls = depth - level;
    uint32_t seen = 0;  // nodes of the next level referenced so far
    size_t child = 0;
    for (const uint8_t mask : a.masks[level]) {
      sink.Mask(cls, mask);
      for (int i = kByteBits[mask]; i > 0; --i) {
        const uint32_t k = a.children[level][child++];
        if (seen > 0) sink.Flag(cls, k < seen);
        if (k < seen) {
          sink.Ref(cls, k, seen);
        } else {
          ++seen;
        }
      }
    }
  }
  for (uint64_t brick : a.leaves) {
    uint8_t cells = 0;
    for (int c = 0; c < 8; ++c) cells = static_cast<uint8_t>(cells | (((brick >> (8 * c)) & 0xFFu) ? 1u << c : 0u));
    sink.Mask(kBrickCellClass, cells);
    for (int c = 0; c < 8; ++c) {
      if ((cells >> c) & 1u) sink.Mask(kVoxelClass, static_cast<uint8_t>(brick >> (8 * c)));
    }
  }
}

template <typename Source>
StatusOr<DagArrays> ReadSymbols(Source& source, int depth, const std::vector<uint64_t>& counts) {
  const int levels = depth - 2;
  DagArrays a;
  a.masks.resize(levels);
  a.children.resize(levels);  // child ordinals, level by level
  // Coders 1 and 3: DecodeDag checked that the payload can hold the declared counts, so reserving
  // them allocates in proportion to the input. Coder 0's counts are bounded only by its header.
  if constexpr (!std::is_same_v<Source, ZstdSource>) {
    for (int level = 0; level < levels; ++level) {
      a.masks[level].reserve(counts[level]);
      a.children[level].reserve(counts[level + 1]);
    }
    a.leaves.reserve(counts[levels]);
  }
  for (int level = 0; level < levels; ++level) {
    const int cls = depth - level;
    uint32_t seen = 0;
    for (uint64_t i = 0; i < counts[level]; ++i) {
      const uint8_t mask = source.Mask(cls);
      if (mask == 0 || source.failed()) return Corrupt("geometry stream holds an empty or missing node mask");
      a.masks[level].push_back(mask);
      for (int c = kByteBits[mask]; c > 0; --c) {
        uint32_t k;
        if (seen > 0 && source.Flag(cls)) {
          k = source.Ref(cls, seen);
          if (k >= seen) return Corrupt("geometry stream refers to a node not yet seen");
        } else {
          k = seen++;
          if (seen > counts[level + 1]) return Corrupt("geometry stream holds more nodes than its header declares");
        }
        a.children[level].push_back(k);
      }
    }
    if (seen != counts[level + 1]) return Corrupt("geometry stream holds fewer nodes than its header declares");
  }
  for (uint64_t i = 0; i < counts[levels]; ++i) {
    const uint8_t cells = source.Mask(kBrickCellClass);
    if (cells == 0) return Corrupt("geometry stream holds an empty brick");
    uint64_t brick = 0;
    for (unsigned rest = cells; rest; rest &= rest - 1) {
      const uint8_t voxels = source.Mask(kVoxelClass);
      if (voxels == 0) return Corrupt("geometry stream holds an empty brick cell");
      brick |= uint64_t{voxels} << (8 * __builtin_ctz(rest));
    }
    a.leaves.push_back(brick);
  }
  if (source.failed()) return Truncated("geometry stream ends early");
  return a;
}

}  // namespace

const char* GeometryCoderName(GeometryCoder coder) {
  switch (coder) {
    case GeometryCoder::kZstd: return "zstd";
    case GeometryCoder::kContext: return "context";
    case GeometryCoder::kSpatial: return "spatial";
    case GeometryCoder::kTable: return "table";
  }
  return "?";
}

StatusOr<std::vector<uint8_t>> EncodeDag(const Svdag& dag, GeometryCoder coder, int version) {
  if (version == kCompactSpatialVersion && (coder == GeometryCoder::kZstd || coder == GeometryCoder::kContext)) version = 5;
  if (version < 1 || (version > kPrefixRefsStreamVersion && version != kCompactSpatialVersion)) return InvalidArgument("geometry stream version " + std::to_string(version) + " is unknown");
  if ((coder == GeometryCoder::kTable) != IsTableVersion(version)) {
    return InvalidArgument("geometry coder 3 is stream versions 6 and 7's, and they are coder 3's");
  }
  RETURN_IF_ERROR(dag.Validate());
  ASSIGN_OR_RETURN(const DagArrays arrays, ToArrays(dag));
  std::vector<uint8_t> out = {static_cast<uint8_t>(version), static_cast<uint8_t>(coder), static_cast<uint8_t>(dag.depth),
                              static_cast<uint8_t>(dag.mode)};
  // Node count of every level (bricks last): bounds the decoder's allocations before it starts.
  for (const auto& masks : arrays.masks) PutVarint(out, masks.size());
  PutVarint(out, arrays.leaves.size());
  if (coder == GeometryCoder::kSpatial) {
    // Its decoder merges equal bricks, so only a DAG that stores each brick once comes back the same
    // (the builder's always does; one decoded from a hostile coder 0/1 stream may not).
    std::unordered_set<uint64_t> seen;
    for (uint64_t brick : arrays.leaves) {
      if (!seen.insert(brick).second) return InvalidArgument("geometry coder 2 needs each brick stored once: one repeats");
    }
    if (version == kCompactSpatialVersion) return EncodeCompactSpatial(arrays, dag.depth, dag.mode);
    ASSIGN_OR_RETURN(const std::vector<uint8_t> payload, EncodeSpatial(arrays, dag.depth, version));
    out.insert(out.end(), payload.begin(), payload.end());
    return out;
  }
  if (coder == GeometryCoder::kZstd) {
    ZstdSink sink;
    WriteSymbols(arrays, sink, dag.depth);
    return sink.Finish(std::move(out));
  }
  if (coder == GeometryCoder::kTable) {
    TableSink sink(dag.depth, version == kPrefixRefsStreamVersion);
    WriteSymbols(arrays, sink, dag.depth);
    return sink.Finish(std::move(out));
  }
  ContextSink sink;
  WriteSymbols(arrays, sink, dag.depth);
  return sink.Finish(std::move(out));
}

StatusOr<Svdag> DecodeDag(std::span<const uint8_t> bytes, uint64_t max_nodes) {
  if (!bytes.empty() && bytes[0] == kCompactSpatialVersion) return DecodeCompactSpatial(bytes, max_nodes);
  if (bytes.size() < 4) return Truncated("geometry stream is shorter than its 4-byte header");
  if (bytes[0] < 1 || bytes[0] > kPrefixRefsStreamVersion) return Corrupt("geometry stream version " + std::to_string(bytes[0]) + " is unknown");
  if (bytes[1] > 3) return Corrupt("geometry stream names unknown coder " + std::to_string(bytes[1]));
  if ((bytes[1] == 3) != IsTableVersion(bytes[0])) {
    return Corrupt("geometry stream version " + std::to_string(bytes[0]) + " names coder " + std::to_string(bytes[1]) +
                   ": coder 3 is versions 6 and 7's, and they are coder 3's");
  }
  const auto coder = static_cast<GeometryCoder>(bytes[1]);
  const int depth = bytes[2];
  if (depth < 2 || depth > kMaxDepth) return Corrupt("geometry stream depth " + std::to_string(depth) + " is outside 2..21");
  if (bytes[3] > 1) return Corrupt("geometry stream names unknown count mode " + std::to_string(bytes[3]));
  const auto mode = static_cast<CountMode>(bytes[3]);

  size_t pos = 4;
  std::vector<uint64_t> counts(static_cast<size_t>(depth - 2) + 1);
  uint64_t total = 0;
  for (size_t level = 0; level < counts.size(); ++level) {
    uint64_t& c = counts[level];
    if (!GetVarint(bytes, pos, c)) return Truncated("geometry stream ends inside its level table");
    if (c == 0 || c > max_nodes - total) return Corrupt("geometry stream declares more nodes than its voxels allow");
    // A node has at most 8 children: a level can hold at most 8 times the nodes of the one above.
    if (level > 0 && c > 8 * counts[level - 1]) return Corrupt("geometry stream declares an impossible node count");
    total += c;
  }
  if (counts[0] != 1) return Corrupt("geometry stream must have exactly one root");

  StatusOr<DagArrays> arrays = Corrupt("unreachable");
  if (coder == GeometryCoder::kZstd) {
    ZstdSource source;
    RETURN_IF_ERROR(source.Open(bytes, pos, counts));
    arrays = ReadSymbols(source, depth, counts);
  } else {
    // The payload's size bounds the nodes it can hold.
    const uint64_t payload = bytes.size() - pos + 8;  // + the zero bytes the decoder may read past the end
    const uint64_t per_byte = coder == GeometryCoder::kContext ? kMaxContextNodesPerByte
                              : coder == GeometryCoder::kTable ? kMaxTableNodesPerByte
                                                               : kMaxSpatialNodesPerByte;
    if (total > payload * per_byte) {
      return Corrupt("geometry stream declares " + std::to_string(total) + " nodes, more than its " +
                     std::to_string(bytes.size() - pos) + " bytes can hold");
    }
    if (coder == GeometryCoder::kContext) {
      ContextSource source(bytes.subspan(pos));
      arrays = ReadSymbols(source, depth, counts);
    } else if (coder == GeometryCoder::kTable) {
      TableSource source;
      RETURN_IF_ERROR(source.Open(bytes.subspan(pos), depth, bytes[0] == kPrefixRefsStreamVersion));
      arrays = ReadSymbols(source, depth, counts);
    } else {
      arrays = DecodeSpatial(bytes.subspan(pos), depth, &counts, max_nodes, bytes[0]);
    }
  }
  if (!arrays.ok()) return arrays.status();
  ASSIGN_OR_RETURN(Svdag dag, FromArrays(*arrays, depth, mode));
  // ReadSymbols' arrays hold what Validate checks by construction (non-empty masks and bricks,
  // references below the next level's declared and reached count, one root), and FromArrays lays
  // them out as valid records (lower-level counts fit 24 bits: at most (8^8 - 1) / 7 below height 8).
  // Validate was 6.5 % of a tile's decode; the spatial decoder's arrays are still checked.
  if (coder == GeometryCoder::kSpatial) RETURN_IF_ERROR(dag.Validate());
  return dag;
}

}  // namespace pointdag
