// Pieces shared by the item decoders of LASzip's layered compressor (POINT14, RGB14, RGBNIR14, BYTE14).
//
// A layered chunk stores each field group in its own layer: a separate arithmetic stream over
// exactly its bytes. An empty layer means the field never changes within the chunk, so it keeps
// the value of the chunk's first (raw) point.
//
// Every item keeps four contexts, one per scanner channel; POINT14 decides the context of each
// point and hands it to the items after it (LASzip's `context` argument).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "pointdag/read/laz/arithmetic_decoder.h"
#include "pointdag/status.h"

namespace pointdag::laz {

constexpr uint32_t kScannerChannels = 4;

// The bytes of one layer, already checked to lie inside the chunk.
struct LayerSpan {
  const uint8_t* data = nullptr;
  uint32_t size = 0;
};

// One layer's stream: decoded only when the layer is not empty.
class Layer {
 public:
  void Start(LayerSpan span) {
    changed_ = span.size != 0;
    if (changed_) decoder_.Init(span.data, span.data + span.size);
  }
  bool changed() const { return changed_; }
  bool overran() const { return changed_ && decoder_.overran(); }
  ArithmeticDecoder& decoder() { return decoder_; }

 private:
  ArithmeticDecoder decoder_;
  bool changed_ = false;
};

// Models LASzip creates on first use (one per value of some previous field). Within a chunk a
// model starts fresh the first time it is used, as LASzip's are (it re-initialises every existing
// model whenever a context starts). Here a context start only bumps the epoch and a model resets
// lazily, so a start costs nothing however many models earlier chunks created.
class LazyModels {
 public:
  LazyModels(size_t count, uint32_t symbols) : symbols_(symbols), models_(count), epochs_(count, 0) {}
  void StartOver() { ++epoch_; }
  // `index` < count (callers index with values masked to the table's size).
  ArithmeticModel& operator[](size_t index) {
    if (!models_[index]) {
      models_[index] = std::make_unique<ArithmeticModel>(symbols_);
    } else if (epochs_[index] != epoch_) {
      models_[index]->Reset();
    }
    epochs_[index] = epoch_;
    return *models_[index];
  }

 private:
  uint32_t symbols_;
  uint32_t epoch_ = 1;
  std::vector<std::unique_ptr<ArithmeticModel>> models_;
  std::vector<uint32_t> epochs_;
};

// How RGB14, RGBNIR14 and BYTE14 follow the context POINT14 hands them. When the context changes
// they switch models; a context used for the first time in the chunk starts from the values of the
// context they leave. Which context's last values predict the point then depends on the item
// version: version 4 uses the new context's; version 3 (a LASzip slip that version 4 fixed, which
// decoding must reproduce) keeps the old context's when the new one was already in use.
class ContextFollower {
 public:
  explicit ContextFollower(uint16_t version) : version_(version) {}
  void Start(uint32_t context) {
    used_.fill(false);
    used_[context] = true;
    current_ = context;
  }
  uint32_t current() const { return current_; }
  // Switches to `context` (< 4); calls init(context, from) for a context new in this chunk.
  // Returns the context whose last values predict this point.
  template <typename Init>
  uint32_t Follow(uint32_t context, Init&& init) {
    uint32_t last = current_;
    if (context != current_) {
      const uint32_t from = current_;
      current_ = context;
      if (!used_[context]) {
        used_[context] = true;
        init(context, from);
        last = context;
      } else if (version_ >= 4) {
        last = context;
      }
    }
    return last;
  }

 private:
  uint16_t version_;
  uint32_t current_ = 0;
  std::array<bool, kScannerChannels> used_{};
};

// LASzip's U8_FOLD for sums of two bytes (and U8_CLAMP'd predictions): the value modulo 256.
inline uint8_t FoldByte(int32_t v) { return static_cast<uint8_t>(v & 0xFF); }
inline int32_t ClampByte(int32_t v) { return v < 0 ? 0 : (v > 255 ? 255 : v); }

// The status of a finished batch: a layer that ran out of bytes is a truncated chunk.
inline Status LayerStatus(const Layer& layer, const char* item, const char* name) {
  if (layer.overran()) {
    return Truncated(std::string("the LAZ chunk's ") + item + " layer '" + name + "' ends before its points do");
  }
  return Status::Ok();
}

}  // namespace pointdag::laz
