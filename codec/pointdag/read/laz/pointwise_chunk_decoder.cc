#include "pointdag/read/laz/pointwise_chunk_decoder.h"

#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "pointdag/read/byte_io.h"
#include "pointdag/read/laz/arithmetic_decoder.h"
#include "pointdag/read/laz/byte_decoder.h"
#include "pointdag/read/laz/gps_time_decoder.h"
#include "pointdag/read/laz/point10_decoder.h"
#include "pointdag/read/laz/rgb12_decoder.h"

namespace pointdag::laz {
namespace {

std::string Num(uint64_t v) { return std::to_string(v); }

class PointwiseChunkDecoder final : public ChunkDecoder {
 public:
  // The items after POINT10, each type at most once (checked by the caller), in the VLR's order.
  explicit PointwiseChunkDecoder(const LaszipVlr& vlr) : record_length_(vlr.record_length()), point10_(decoder_) {
    size_t offset = Point10Decoder::kSize;
    for (size_t i = 1; i < vlr.items.size(); ++i) {
      const Item& item = vlr.items[i];
      if (item.type == ItemType::kGpsTime11) gps_.emplace(decoder_, GpsTimeCodes::kGpsTime11);
      if (item.type == ItemType::kRgb12) rgb_.emplace(decoder_);
      if (item.type == ItemType::kByte) bytes_.emplace(decoder_, item.size);
      slots_.push_back({item.type, offset});
      offset += item.size;
    }
  }

  Status Start(const uint8_t* data, size_t size, uint64_t points) override {
    data_ = data;
    size_ = size;
    points_ = points;
    decoded_ = 0;
    if (points > 0 && size < record_length_) {
      points_ = 0;
      return Truncated("the chunk holds " + Num(size) + " bytes, fewer than its first point's " +
                       Num(record_length_));
    }
    return Status::Ok();
  }

  Status Decode(uint8_t* out, size_t n) override {
    if (n > points_ - decoded_) {
      return Internal("asked for " + Num(n) + " points of a chunk with " + Num(points_ - decoded_) + " left");
    }
    if (n == 0) return Status::Ok();
    size_t i = 0;
    if (decoded_ == 0) {  // the raw first point starts every model and then the stream
      std::memcpy(out, data_, record_length_);
      point10_.Init(out);
      for (const Slot& slot : slots_) InitItem(slot, out + slot.offset);
      decoder_.Init(data_ + record_length_, data_ + size_);
      i = 1;
    }
    for (; i < n; ++i) {
      uint8_t* record = out + i * record_length_;
      point10_.Decode(record);
      for (const Slot& slot : slots_) {
        // In a stream cut short anything may follow: that is reported as truncation below.
        if (!DecodeItem(slot, record + slot.offset) && !decoder_.overran()) {
          return Malformed("point " + Num(decoded_ + i) + " of the chunk switches GPS time sequences " +
                           "more often than LASzip writes");
        }
      }
    }
    decoded_ += n;
    if (decoder_.overran()) {
      return Truncated("the chunk's compressed stream ends before its " + Num(points_) + " points are decoded");
    }
    return Status::Ok();
  }

  size_t BytesUsed() const override { return points_ == 0 ? 0 : record_length_ + decoder_.consumed(); }

 private:
  struct Slot {
    ItemType type;
    size_t offset;  // in the record
  };

  void InitItem(const Slot& slot, const uint8_t* item) {
    switch (slot.type) {
      case ItemType::kGpsTime11: gps_->Reset(LoadLE<uint64_t>(item)); break;
      case ItemType::kRgb12: rgb_->Init(item); break;
      default: bytes_->Init(item); break;
    }
  }

  bool DecodeItem(const Slot& slot, uint8_t* out) {
    switch (slot.type) {
      case ItemType::kGpsTime11: {
        uint64_t time = 0;
        if (!gps_->Decode(time)) return false;
        std::memcpy(out, &time, sizeof(time));
        return true;
      }
      case ItemType::kRgb12: rgb_->Decode(out); return true;
      default: bytes_->Decode(out); return true;
    }
  }

  const size_t record_length_;
  ArithmeticDecoder decoder_;  // before the items, which keep a reference to it
  Point10Decoder point10_;
  std::optional<GpsTimeDecoder> gps_;
  std::optional<Rgb12Decoder> rgb_;
  std::optional<ByteDecoder> bytes_;
  std::vector<Slot> slots_;

  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  uint64_t points_ = 0, decoded_ = 0;
};

}  // namespace

StatusOr<std::unique_ptr<ChunkDecoder>> MakePointwiseChunkDecoder(const LaszipVlr& vlr) {
  if (vlr.compressor != Compressor::kPointwiseChunked) {
    return Internal("the point-wise chunk decoder was asked for another LAZ compressor");
  }
  if (vlr.items.empty() || vlr.items.front().type != ItemType::kPoint10) {
    return Malformed("a point-wise compressed LAZ file's first item must be POINT10");
  }
  bool seen[3] = {false, false, false};  // GPSTIME11, RGB12, BYTE
  for (size_t i = 1; i < vlr.items.size(); ++i) {
    const Item& item = vlr.items[i];
    int kind;
    switch (item.type) {
      case ItemType::kGpsTime11: kind = 0; break;
      case ItemType::kRgb12: kind = 1; break;
      case ItemType::kByte: kind = 2; break;
      default: return Malformed("LAZ item " + ItemName(item) + " cannot follow POINT10 in a point-wise file");
    }
    if (seen[kind]) return Unsupported("the LAZ items list " + ItemName(item) + " twice, which LASzip never writes");
    seen[kind] = true;
    if (item.type == ItemType::kByte && item.size > ByteDecoder::kMaxCount) {
      return ResourceLimit("LAZ item " + ItemName(item) + " has more than " + Num(ByteDecoder::kMaxCount) +
                           " extra bytes per point");
    }
  }
  return std::unique_ptr<ChunkDecoder>(std::make_unique<PointwiseChunkDecoder>(vlr));
}

}  // namespace pointdag::laz
