// Geometry coder 3 (proto/PDAG_FORMAT.md §2.2, stream versions 6 and 7), for tiles that every client
// decodes on every view: the symbols of coders 0 and 1 in their order, each node mask one lookup in
// a canonical prefix code per class (its height) sent with the stream, instead of eight adaptive
// binary decisions; flags (and, version 6, references) stay range-coded (coder 1's models) in a section
// of their own.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/entropy/code_lengths.h"
#include "pointdag/entropy/prefix_code.h"
#include "pointdag/status.h"

namespace pointdag {

// Every mask costs at least one bit: a byte of the stream holds at most 8 masks, hence 8 nodes.
constexpr uint64_t kMaxTableNodesPerByte = 8;

// Models of the range-coded section, fresh per stream: the code lengths of the mask classes, then
// flags and references (as coder 1's). `classes`: the depth D + 1 (classes 1..D).
struct TableModels {
  // Version 7 (`prefix_refs`) range-codes no references: no gamma models (10 KB a tile) to set up.
  TableModels(int classes, bool prefix_refs) : flag(classes), ref(prefix_refs ? 0 : classes) {}
  CodeLengthModels code;  // each class's code lengths (or 8 bits a mask)
  std::vector<BitModel> flag;
  std::vector<GammaModel> ref;
};

// Stream version 7 (tiles): a reference k < bound as v = k + 1 of L = bit_width(v) bits, in the
// prefix section in stream order: one symbol (bit_width(bound) - L) * 4 + the two bits below v's
// leading one (fewer when L < 3) of one canonical code per stream, then v's remaining L - 3 bits raw
// (most significant first). Decoding one costs a lookup instead of a gamma code's adaptive decisions.
constexpr int RefSymbol(uint32_t v, uint32_t bound) {
  const int length = std::bit_width(v), top = std::min(length - 1, 2);
  return (std::bit_width(bound) - length) * 4 + static_cast<int>((v >> (length - 1 - top)) & ((1u << top) - 1));
}

class TableSink {
 public:
  TableSink(int depth, bool prefix_refs) : depth_(depth), prefix_refs_(prefix_refs) {}
  void Mask(int cls, uint8_t m) { masks_.push_back({static_cast<uint8_t>(cls), m, 0, 0}); }
  void Flag(int cls, bool back) { events_.push_back({static_cast<uint8_t>(cls), back ? 1u : 0u, 0}); }
  void Ref(int cls, uint32_t ordinal, uint32_t bound) {
    if (prefix_refs_) {
      masks_.push_back({static_cast<uint8_t>(cls), 0, ordinal + 1, bound});
    } else {
      events_.push_back({static_cast<uint8_t>(cls), ordinal, bound});
    }
  }
  StatusOr<std::vector<uint8_t>> Finish(std::vector<uint8_t> out);

 private:
  struct MaskSymbol {  // a mask (bound 0) or, version 7, a reference's v = ordinal + 1
    uint8_t cls, mask;
    uint32_t v, bound;
  };
  struct Event {  // a flag (bound 0) or a reference
    uint8_t cls;
    uint32_t value, bound;
  };
  int depth_;
  bool prefix_refs_;
  std::vector<MaskSymbol> masks_;
  std::vector<Event> events_;
};

class TableSource {
 public:
  // Reads the section lengths and the code tables from `payload` (all that follows the level table).
  Status Open(std::span<const uint8_t> payload, int depth, bool prefix_refs);
  uint8_t Mask(int cls) {
    const int s = masks_->Get(*tables_[cls]);
    failed_ |= s < 0;
    return static_cast<uint8_t>(s < 0 ? 0 : s);
  }
  bool Flag(int cls) { return rc_->Decode(models_->flag[cls]) != 0; }
  uint32_t Ref(int cls, uint32_t bound) {
    if (!prefix_refs_) return DecodeGamma(*rc_, models_->ref[cls], std::bit_width(bound)) - 1;
    const int s = masks_->Get(*ref_table_);
    const int length = std::bit_width(bound) - (s >> 2), top = std::min(length - 1, 2);
    if (s < 0 || length < 1 || (s & 3) >> top) {
      failed_ = true;
      return bound;
    }
    const uint32_t high = 1u << top | static_cast<uint32_t>(s & 3);
    return (high << (length - 1 - top) | masks_->Bits(length - 1 - top)) - 1;
  }
  bool failed() const { return failed_ || rc_->overrun() || masks_->overrun(); }

 private:
  std::vector<PrefixTable> built_;  // the tables of the codes sent
  std::vector<const PrefixTable*> tables_;
  const PrefixTable* ref_table_ = nullptr;
  bool prefix_refs_ = false;
  std::unique_ptr<TableModels> models_;
  std::optional<BinaryRangeDecoder> rc_;
  std::optional<PrefixDecoder> masks_;
  bool failed_ = false;
};

}  // namespace pointdag
