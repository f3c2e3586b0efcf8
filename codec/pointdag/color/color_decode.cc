// DecodeColors (declared in color_codec.h): the colors section's reader, apart from the encoders so
// that a decoder-only build (the WebAssembly one, web/wasm) links without them.
#include <zstd.h>

#include "pointdag/color/astc_mapping.h"
#include "pointdag/color/block_codec.h"
#include "pointdag/color/color_codec.h"
#include "pointdag/color/hierarchical_colors.h"
#include "pointdag/color/lossless_context.h"
#include "pointdag/entropy/zstd_stream.h"

namespace pointdag {
namespace {

// Version 1 (before the context coder): planar differences in one zstd frame.
StatusOr<std::vector<Rgb8>> DecodeLosslessZstd(std::span<const uint8_t> payload, uint64_t count) {
  // The frame's content-size field only rejects early; the output grows with what really comes out.
  if (ZSTD_getFrameContentSize(payload.data(), payload.size()) != 3 * count) {
    return Corrupt("lossless colors do not hold one RGB per voxel");
  }
  std::vector<uint8_t> planes;
  if (Status s = DecompressBounded(payload, 3 * count, planes, "lossless colors"); !s.ok()) return Corrupt(s.message());
  if (planes.size() != 3 * count) return Corrupt("lossless colors do not hold one RGB per voxel");
  std::vector<Rgb8> colors(count);
  Rgb8 prev{};
  for (size_t i = 0; i < count; ++i) {
    prev = {static_cast<uint8_t>(prev.r + planes[i]), static_cast<uint8_t>(prev.g + planes[count + i]),
            static_cast<uint8_t>(prev.b + planes[2 * count + i])};
    colors[i] = prev;
  }
  return colors;
}

}  // namespace

StatusOr<std::vector<Rgb8>> DecodeColors(std::span<const uint8_t> section, uint64_t count,
                                         std::span<const uint64_t> morton) {
  if (section.empty()) return Truncated("colors section is empty");
  if (count == 0) return Corrupt("a colors section for no voxels");
  if (count > kMaxColors) return ResourceLimit(std::to_string(count) + " colors are more than a colors section may hold");
  const auto payload = section.subspan(1);
  switch (static_cast<ColorCodec>(section[0] & ~kVoxelColorsOnly)) {
    case ColorCodec::kRaw: {
      if (payload.size() != 3 * count) return Corrupt("raw colors do not hold one RGB per voxel");
      std::vector<Rgb8> colors(count);
      for (size_t i = 0; i < count; ++i) colors[i] = {payload[3 * i], payload[3 * i + 1], payload[3 * i + 2]};
      return colors;
    }
    case ColorCodec::kLossless:
      if (IsLosslessContextPayload(payload)) return DecodeLosslessContext(payload, count, morton);
      return DecodeLosslessZstd(payload, count);
    case ColorCodec::kFixedRate:
    case ColorCodec::kVariableRate: {
      ASSIGN_OR_RETURN(BlockColorDecoder decoder, BlockColorDecoder::Open(payload, count, morton));
      return decoder.DecodeAll();
    }
    case ColorCodec::kPng:
    case ColorCodec::kJpeg:
    case ColorCodec::kWebp:
      return DecodeColorImage(payload, count);
    case ColorCodec::kAstc:
      return DecodeColorAstc(payload, count);
    case ColorCodec::kHierarchical:
      return DecodeHierarchicalColors(payload, count, morton);
  }
  return Corrupt("colors section names unknown codec " + std::to_string(section[0] & ~kVoxelColorsOnly));
}

}  // namespace pointdag
