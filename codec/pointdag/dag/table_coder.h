// Geometry coder 3 (proto/PDAG_FORMAT.md §2.2, stream version 6), for tiles that every client
// decodes on every view: the symbols of coders 0 and 1 in their order, each node mask one lookup in
// a canonical prefix code per class (its height) sent with the stream, instead of eight adaptive
// binary decisions; flags and references stay range-coded (coder 1's models) in a section of their own.
#pragma once

#include <bit>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "pointdag/entropy/adaptive_codes.h"
#include "pointdag/entropy/prefix_code.h"
#include "pointdag/status.h"

namespace pointdag {

// Every mask costs at least one bit: a byte of the stream holds at most 8 masks, hence 8 nodes.
constexpr uint64_t kMaxTableNodesPerByte = 8;

// Models of the range-coded section, fresh per stream: the code lengths of the mask classes, then
// flags and references (as coder 1's). `classes`: the depth D + 1 (classes 1..D).
struct TableModels {
  explicit TableModels(int classes) : flag(classes), ref(classes) {}
  BitModel coded;                                 // 1: the class's code lengths follow, 0: 8 bits a mask
  std::array<BitTreeModel<4>, kPrefixCodeBits + 1> length;  // by the previous symbol's length
  std::vector<BitModel> flag;
  std::vector<GammaModel> ref;
};

class TableSink {
 public:
  explicit TableSink(int depth) : depth_(depth) {}
  void Mask(int cls, uint8_t m) { masks_.push_back({static_cast<uint8_t>(cls), m}); }
  void Flag(int cls, bool back) { events_.push_back({static_cast<uint8_t>(cls), back ? 1u : 0u, 0}); }
  void Ref(int cls, uint32_t ordinal, uint32_t bound) { events_.push_back({static_cast<uint8_t>(cls), ordinal, bound}); }
  StatusOr<std::vector<uint8_t>> Finish(std::vector<uint8_t> out);

 private:
  struct MaskSymbol {
    uint8_t cls, mask;
  };
  struct Event {  // a flag (bound 0) or a reference
    uint8_t cls;
    uint32_t value, bound;
  };
  int depth_;
  std::vector<MaskSymbol> masks_;
  std::vector<Event> events_;
};

class TableSource {
 public:
  // Reads the section lengths and the code tables from `payload` (all that follows the level table).
  Status Open(std::span<const uint8_t> payload, int depth);
  uint8_t Mask(int cls) {
    const int s = masks_->Get(tables_[cls]);
    failed_ |= s < 0;
    return static_cast<uint8_t>(s < 0 ? 0 : s);
  }
  bool Flag(int cls) { return rc_->Decode(models_->flag[cls]) != 0; }
  uint32_t Ref(int cls, uint32_t bound) { return DecodeGamma(*rc_, models_->ref[cls], std::bit_width(bound)) - 1; }
  bool failed() const { return failed_ || rc_->overrun() || masks_->overrun(); }

 private:
  std::vector<PrefixTable> tables_;
  std::unique_ptr<TableModels> models_;
  std::unique_ptr<BinaryRangeDecoder> rc_;
  std::unique_ptr<PrefixDecoder> masks_;
  bool failed_ = false;
};

}  // namespace pointdag
