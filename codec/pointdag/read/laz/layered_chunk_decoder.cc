#include "pointdag/read/laz/layered_chunk_decoder.h"

#include <cstring>
#include <string>
#include <vector>

#include "pointdag/read/byte_io.h"
#include "pointdag/read/laz/byte14_decoder.h"
#include "pointdag/read/laz/point14_decoder.h"
#include "pointdag/read/laz/rgb14_decoder.h"

namespace pointdag::laz {
namespace {

std::string Num(uint64_t v) { return std::to_string(v); }

// The items are concrete members, not a list of virtual item decoders: a point costs three
// direct calls at most.
class LayeredChunkDecoder final : public ChunkDecoder {
 public:
  LayeredChunkDecoder(uint16_t point_version, std::unique_ptr<Rgb14Decoder> rgb, std::unique_ptr<Byte14Decoder> bytes)
      : point14_(point_version), rgb_(std::move(rgb)), bytes_(std::move(bytes)) {
    record_length_ = Point14Decoder::kSize;
    layer_count_ = Point14Decoder::kLayers;
    if (rgb_) {
      record_length_ += rgb_->size();
      layer_count_ += rgb_->layer_count();
    }
    bytes_offset_ = record_length_;
    if (bytes_) {
      record_length_ += bytes_->size();
      layer_count_ += bytes_->layer_count();
    }
    layers_.resize(layer_count_);
  }

  Status Start(const uint8_t* data, size_t size, uint64_t points) override {
    left_ = 0;
    bytes_used_ = 0;
    if (points == 0) return Malformed("a LAZ chunk of 0 points");
    const size_t head = size_t{record_length_} + 4 + size_t{4} * layer_count_;
    if (size < head) {
      return Truncated("the LAZ chunk is " + Num(size) + " bytes, too short for its first point and its " +
                       Num(layer_count_) + " layer sizes (" + Num(head) + " bytes)");
    }
    const uint32_t count = LoadLE<uint32_t>(data + record_length_);
    if (count != points) {
      return Malformed("the LAZ chunk says it holds " + Num(count) + " points where the file says " + Num(points));
    }
    const uint8_t* sizes = data + record_length_ + 4;
    const uint8_t* next = data + head;
    size_t remaining = size - head;
    for (uint32_t i = 0; i < layer_count_; ++i) {
      const uint32_t layer_size = LoadLE<uint32_t>(sizes + size_t{4} * i);
      if (layer_size > remaining) {
        return Truncated("layer " + Num(i) + " of the LAZ chunk is " + Num(layer_size) + " bytes but only " +
                         Num(remaining) + " of the chunk's bytes are left");
      }
      layers_[i] = {next, layer_size};
      next += layer_size;
      remaining -= layer_size;
    }
    if (points > 1 && layers_[0].size == 0) {
      return Truncated("the LAZ chunk's POINT14 coordinate layer is empty but the chunk holds " + Num(points) +
                       " points");
    }

    const uint32_t context = point14_.Start(data, layers_.data());
    const uint8_t* item = data + Point14Decoder::kSize;
    const LayerSpan* layer = layers_.data() + Point14Decoder::kLayers;
    if (rgb_) {
      rgb_->Start(item, layer, context);
      item += rgb_->size();
      layer += rgb_->layer_count();
    }
    if (bytes_) bytes_->Start(item, layer, context);
    first_ = data;
    left_ = points;
    first_pending_ = true;
    bytes_used_ = static_cast<size_t>(next - data);
    return Status::Ok();
  }

  Status Decode(uint8_t* out, size_t n) override {
    if (n > left_) {
      return InvalidArgument("asked for " + Num(n) + " points of a LAZ chunk with " + Num(left_) + " left");
    }
    for (size_t i = 0; i < n; ++i, out += record_length_) {
      if (first_pending_) {
        std::memcpy(out, first_, record_length_);
        first_pending_ = false;
        continue;
      }
      uint32_t context = 0;  // LASzip's reader starts every point at context 0
      point14_.Decode(out, context);
      if (rgb_) rgb_->Decode(out + Point14Decoder::kSize, context);
      if (bytes_) bytes_->Decode(out + bytes_offset_, context);
    }
    left_ -= n;
    RETURN_IF_ERROR(point14_.status());
    if (rgb_) RETURN_IF_ERROR(rgb_->status());
    if (bytes_) RETURN_IF_ERROR(bytes_->status());
    return Status::Ok();
  }

  size_t BytesUsed() const override { return bytes_used_; }

 private:
  Point14Decoder point14_;
  std::unique_ptr<Rgb14Decoder> rgb_;     // null without colour
  std::unique_ptr<Byte14Decoder> bytes_;  // null without extra bytes
  uint32_t record_length_ = 0, bytes_offset_ = 0, layer_count_ = 0;
  std::vector<LayerSpan> layers_;
  const uint8_t* first_ = nullptr;
  uint64_t left_ = 0;
  bool first_pending_ = false;
  size_t bytes_used_ = 0;
};

std::string ItemList(const LaszipVlr& vlr) {
  std::string list;
  for (const Item& item : vlr.items) list += (list.empty() ? "" : ", ") + ItemName(item);
  return list;
}

}  // namespace

StatusOr<std::unique_ptr<ChunkDecoder>> MakeLayeredChunkDecoder(const LaszipVlr& vlr) {
  const std::vector<Item>& items = vlr.items;
  const auto malformed = [&vlr] {
    return Malformed("the LASzip VLR's items (" + ItemList(vlr) +
                     ") are not a layered record LASzip writes: POINT14, then RGB14 or RGBNIR14, then BYTE14");
  };
  for (const Item& item : items) {
    if (item.type == ItemType::kWavepacket14) {
      return Unsupported("LAZ item " + ItemName(item) +
                         " (full-waveform packets, point formats 9 and 10) is not supported");
    }
    if (item.version != 3 && item.version != 4) {
      return Unsupported("LAZ item " + ItemName(item) + " uses LASzip's item version " + Num(item.version) +
                         "; versions 3 and 4 are supported");
    }
  }
  size_t i = 0;
  if (items.empty() || items[0].type != ItemType::kPoint14 || items[0].size != Point14Decoder::kSize) {
    return malformed();
  }
  const uint16_t point_version = items[i++].version;
  std::unique_ptr<Rgb14Decoder> rgb;
  if (i < items.size() && (items[i].type == ItemType::kRgb14 || items[i].type == ItemType::kRgbNir14)) {
    rgb = std::make_unique<Rgb14Decoder>(items[i].type == ItemType::kRgbNir14, items[i].version);
    if (items[i++].size != rgb->size()) return malformed();
  }
  std::unique_ptr<Byte14Decoder> bytes;
  if (i < items.size() && items[i].type == ItemType::kByte14 && items[i].size != 0) {
    bytes = std::make_unique<Byte14Decoder>(items[i].size, items[i].version);
    ++i;
  }
  if (i != items.size()) return malformed();
  return std::unique_ptr<ChunkDecoder>(
      std::make_unique<LayeredChunkDecoder>(point_version, std::move(rgb), std::move(bytes)));
}

}  // namespace pointdag::laz
