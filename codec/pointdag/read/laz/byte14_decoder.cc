#include "pointdag/read/laz/byte14_decoder.h"

#include <cstring>
#include <string>

namespace pointdag::laz {

Byte14Decoder::Byte14Decoder(uint32_t count, uint16_t version) : count_(count), follower_(version), layers_(count) {
  changed_.reserve(count);
  for (uint32_t c = 0; c < kScannerChannels; ++c) models_.emplace_back(count, 256);
  for (auto& last : last_) last.resize(count);
}

void Byte14Decoder::InitContext(uint32_t context, uint32_t from) {
  models_[context].StartOver();
  if (context != from) last_[context] = last_[from];
}

void Byte14Decoder::Start(const uint8_t* first, const LayerSpan* layers, uint32_t context) {
  changed_.clear();
  for (uint32_t i = 0; i < count_; ++i) {
    layers_[i].Start(layers[i]);
    if (layers_[i].changed()) changed_.push_back(i);
  }
  std::memcpy(last_[context].data(), first, count_);
  follower_.Start(context);
  InitContext(context, context);
}

void Byte14Decoder::Decode(uint8_t* item, uint32_t context) {
  const uint32_t last = follower_.Follow(context, [this](uint32_t to, uint32_t from) { InitContext(to, from); });
  LazyModels& models = models_[follower_.current()];
  uint8_t* values = last_[last].data();
  for (const uint32_t i : changed_) {
    values[i] = FoldByte(values[i] + static_cast<int32_t>(layers_[i].decoder().DecodeSymbol(models[i])));
  }
  std::memcpy(item, values, count_);
}

Status Byte14Decoder::status() const {
  for (const uint32_t i : changed_) {
    if (layers_[i].overran()) return LayerStatus(layers_[i], "BYTE14", ("extra byte " + std::to_string(i)).c_str());
  }
  return Status::Ok();
}

}  // namespace pointdag::laz
