#include "pointdag/read/laz/laszip_vlr.h"

#include "pointdag/read/byte_io.h"

namespace pointdag::laz {
namespace {

constexpr size_t kFixedPart = 34;  // the VLR's fields before the item list
constexpr size_t kItemBytes = 6;

const char* TypeName(ItemType type) {
  switch (type) {
    case ItemType::kByte: return "BYTE";
    case ItemType::kShort: return "SHORT";
    case ItemType::kInt: return "INT";
    case ItemType::kLong: return "LONG";
    case ItemType::kFloat: return "FLOAT";
    case ItemType::kDouble: return "DOUBLE";
    case ItemType::kPoint10: return "POINT10";
    case ItemType::kGpsTime11: return "GPSTIME11";
    case ItemType::kRgb12: return "RGB12";
    case ItemType::kWavepacket13: return "WAVEPACKET13";
    case ItemType::kPoint14: return "POINT14";
    case ItemType::kRgb14: return "RGB14";
    case ItemType::kRgbNir14: return "RGBNIR14";
    case ItemType::kWavepacket14: return "WAVEPACKET14";
    case ItemType::kByte14: return "BYTE14";
  }
  return "UNKNOWN";
}

// The fixed size of each item type; 0 for the byte items, whose size is the extra bytes' count.
uint16_t FixedSize(ItemType type) {
  switch (type) {
    case ItemType::kPoint10: return 20;
    case ItemType::kGpsTime11: return 8;
    case ItemType::kRgb12: return 6;
    case ItemType::kWavepacket13: return 29;
    case ItemType::kPoint14: return 30;
    case ItemType::kRgb14: return 6;
    case ItemType::kRgbNir14: return 8;
    case ItemType::kWavepacket14: return 29;
    default: return 0;
  }
}

std::string Num(uint64_t v) { return std::to_string(v); }

// Which items each compressor decodes here, and in which versions.
Status CheckItem(const Item& item, Compressor compressor) {
  const std::string name = ItemName(item);
  if (item.type == ItemType::kWavepacket13 || item.type == ItemType::kWavepacket14) {
    return Unsupported("LAZ item " + name + " (full-waveform packets, point formats 4, 5, 9 and 10) is not supported");
  }
  if (compressor == Compressor::kPointwiseChunked) {
    const bool known = item.type == ItemType::kPoint10 || item.type == ItemType::kGpsTime11 ||
                       item.type == ItemType::kRgb12 || item.type == ItemType::kByte;
    if (!known) return Malformed("LAZ item " + name + " cannot appear in a point-wise compressed file");
    if (item.version != 2) {
      return Unsupported("LAZ item " + name + " uses LASzip's item version " + Num(item.version) +
                         "; version 2 (LASzip 2.0 and later) is supported");
    }
  } else {
    const bool known = item.type == ItemType::kPoint14 || item.type == ItemType::kRgb14 ||
                       item.type == ItemType::kRgbNir14 || item.type == ItemType::kByte14;
    if (!known) return Malformed("LAZ item " + name + " cannot appear in a layered (LAS 1.4) compressed file");
    if (item.version != 3 && item.version != 4) {
      return Unsupported("LAZ item " + name + " uses LASzip's item version " + Num(item.version) +
                         "; versions 3 and 4 are supported");
    }
  }
  return Status::Ok();
}

}  // namespace

std::string ItemName(const Item& item) {
  return std::string(TypeName(item.type)) + ":" + Num(item.size) + ":v" + Num(item.version);
}

uint32_t LaszipVlr::record_length() const {
  uint32_t sum = 0;
  for (const Item& item : items) sum += item.size;
  return sum;
}

StatusOr<LaszipVlr> ParseLaszipVlr(const std::vector<unsigned char>& payload, uint32_t record_length) {
  if (payload.size() < kFixedPart) {
    return Malformed("the LASzip VLR is " + Num(payload.size()) + " bytes, shorter than its 34-byte header");
  }
  const unsigned char* p = payload.data();
  LaszipVlr vlr;
  const uint16_t compressor = LoadLE<uint16_t>(p);
  vlr.coder = LoadLE<uint16_t>(p + 2);
  vlr.version_major = p[4];
  vlr.version_minor = p[5];
  vlr.version_revision = LoadLE<uint16_t>(p + 6);
  vlr.options = LoadLE<uint32_t>(p + 8);
  vlr.chunk_size = LoadLE<uint32_t>(p + 12);
  const uint16_t item_count = LoadLE<uint16_t>(p + 32);
  if (kFixedPart + size_t{item_count} * kItemBytes > payload.size()) {
    return Malformed("the LASzip VLR lists " + Num(item_count) + " items but holds room for " +
                     Num((payload.size() - kFixedPart) / kItemBytes));
  }
  if (item_count == 0) return Malformed("the LASzip VLR lists no items");
  for (size_t i = 0; i < item_count; ++i) {
    const unsigned char* q = p + kFixedPart + i * kItemBytes;
    const uint16_t type = LoadLE<uint16_t>(q);
    if (type > static_cast<uint16_t>(ItemType::kByte14)) {
      return Malformed("LASzip VLR item " + Num(i) + " has unknown type " + Num(type));
    }
    Item item{static_cast<ItemType>(type), LoadLE<uint16_t>(q + 2), LoadLE<uint16_t>(q + 4)};
    const uint16_t fixed = FixedSize(item.type);
    if ((fixed != 0 && item.size != fixed) || item.size == 0) {
      return Malformed("LASzip VLR item " + ItemName(item) + " has the wrong size for its type");
    }
    vlr.items.push_back(item);
  }
  if (vlr.record_length() != record_length) {
    return Malformed("the LASzip VLR's items cover " + Num(vlr.record_length()) +
                     " bytes but the LAS header's point record length is " + Num(record_length));
  }
  if (vlr.coder != 0) return Unsupported("LAZ coder " + Num(vlr.coder) + " is unknown (0, arithmetic, is LASzip's)");
  switch (compressor) {
    case 1:
      return Unsupported("this LAZ file uses LASzip 1.x's unchunked point-wise compressor (LASzip " +
                         Num(vlr.version_major) + "." + Num(vlr.version_minor) +
                         "); re-compress it with LASzip 2 or later (`laszip -i in.laz -o out.laz`)");
    case 2: vlr.compressor = Compressor::kPointwiseChunked; break;
    case 3: vlr.compressor = Compressor::kLayeredChunked; break;
    default: return Malformed("LAZ compressor " + Num(compressor) + " is unknown (2: point-wise, 3: layered)");
  }
  if (vlr.chunk_size == 0) return Malformed("the LASzip VLR declares chunks of 0 points");
  for (const Item& item : vlr.items) RETURN_IF_ERROR(CheckItem(item, vlr.compressor));
  const ItemType first = vlr.items.front().type;
  if (first != ItemType::kPoint10 && first != ItemType::kPoint14) {
    return Malformed("the LASzip VLR's first item is " + ItemName(vlr.items.front()) + ", not POINT10 or POINT14");
  }
  return vlr;
}

}  // namespace pointdag::laz
