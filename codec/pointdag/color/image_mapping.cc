#include "pointdag/color/image_mapping.h"

#include <algorithm>
#include <array>
#include <bit>

#include "pointdag/entropy/varint.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

// Our own look at the image before its library's: the format's signature, and for PNG the size
// that deflate (at most 1032:1) can expand its bytes to. The side itself is already bound to the
// validated color count; JPEG and WebP stop at 16384 (the encoder's limit too).
Status CheckImageBytes(std::span<const uint8_t> image, ImageFormat format, uint64_t side) {
  static constexpr uint8_t kPngMagic[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  static constexpr uint8_t kJpegMagic[] = {0xFF, 0xD8, 0xFF};
  const auto starts_with = [&](std::span<const uint8_t> magic, size_t at = 0) {
    return image.size() >= at + magic.size() && std::equal(magic.begin(), magic.end(), image.begin() + static_cast<long>(at));
  };
  bool signed_ok = false;
  switch (format) {
    case ImageFormat::kPng: signed_ok = starts_with(kPngMagic); break;
    case ImageFormat::kJpeg: signed_ok = starts_with(kJpegMagic); break;
    case ImageFormat::kWebp: {
      static constexpr uint8_t kRiff[] = {'R', 'I', 'F', 'F'}, kWebp[] = {'W', 'E', 'B', 'P'};
      signed_ok = starts_with(kRiff) && starts_with(kWebp, 8);
      break;
    }
  }
  if (!signed_ok) return Corrupt(std::string("color image is not a ") + ImageFormatName(format) + " file");
  if (format != ImageFormat::kPng && side > kMaxLossyTextureSide) return Corrupt("color image is larger than JPEG/WebP allow");
  if (format == ImageFormat::kPng && side * (3 * side + 1) > 1032 * image.size() + 65536) {
    return Corrupt("color PNG is too small to hold a " + std::to_string(side) + "x" + std::to_string(side) + " image");
  }
  return Status::Ok();
}

}  // namespace

uint32_t TextureSide(uint64_t count) {
  uint32_t side = 1;
  while (uint64_t{side} * side < count && side < kMaxTextureSide) side <<= 1;
  return side;
}

std::vector<uint8_t> LayOutTexture(std::span<const Rgb8> colors, Curve curve, uint32_t side, int channels) {
  std::vector<uint8_t> pixels(size_t{side} * side * static_cast<size_t>(channels), 255);
  for (uint64_t i = 0; i < uint64_t{side} * side; ++i) {
    const Rgb8 c = colors[std::min<uint64_t>(i, colors.size() - 1)];
    const auto [x, y] = CurvePosition(curve, i, side);
    uint8_t* p = &pixels[(size_t{y} * side + x) * static_cast<size_t>(channels)];
    p[0] = c.r, p[1] = c.g, p[2] = c.b;
  }
  return pixels;
}

std::vector<Rgb8> GatherTexture(std::span<const uint8_t> pixels, Curve curve, uint32_t side, int channels, uint64_t count) {
  std::vector<Rgb8> colors(count);
  for (uint64_t i = 0; i < count; ++i) {
    const auto [x, y] = CurvePosition(curve, i, side);
    const uint8_t* p = &pixels[(size_t{y} * side + x) * static_cast<size_t>(channels)];
    colors[i] = {p[0], p[1], p[2]};
  }
  return colors;
}

const char* CurveName(Curve curve) { return curve == Curve::kMorton ? "morton" : "hilbert"; }

std::array<uint32_t, 2> CurvePosition(Curve curve, uint64_t i, uint32_t side) {
  if (curve == Curve::kMorton) {
    uint32_t x = 0, y = 0;
    for (int b = 0; b < 32; ++b) {
      x |= static_cast<uint32_t>((i >> (2 * b + 1)) & 1u) << b;
      y |= static_cast<uint32_t>((i >> (2 * b)) & 1u) << b;
    }
    return {x, y};
  }
  // Hilbert: the classic iterative d -> (x, y) walk, quadrant by quadrant.
  uint32_t x = 0, y = 0;
  uint64_t t = i;
  for (uint32_t s = 1; s < side; s <<= 1) {
    const uint32_t rx = static_cast<uint32_t>((t >> 1) & 1u);
    const uint32_t ry = static_cast<uint32_t>((t ^ rx) & 1u);
    if (ry == 0) {
      if (rx == 1) {
        x = s - 1 - x;
        y = s - 1 - y;
      }
      std::swap(x, y);
    }
    x += s * rx;
    y += s * ry;
    t >>= 2;
  }
  return {x, y};
}

StatusOr<std::vector<uint8_t>> EncodeColorImage(std::span<const Rgb8> colors, Curve curve, ImageFormat format,
                                                int quality) {
  if (colors.empty()) return InvalidArgument("no colors to map");
  const uint32_t side = TextureSide(colors.size());
  if (side > kMaxLossyTextureSide && format != ImageFormat::kPng) return ResourceLimit("texture too large for JPEG/WebP");
  const std::vector<uint8_t> pixels = LayOutTexture(colors, curve, side, 3);
  ASSIGN_OR_RETURN(std::vector<uint8_t> image, EncodeImageFile(pixels, side, format, quality));
  std::vector<uint8_t> payload = {static_cast<uint8_t>(curve), static_cast<uint8_t>(format)};
  PutVarint(payload, side);
  payload.insert(payload.end(), image.begin(), image.end());
  return payload;
}

StatusOr<std::vector<Rgb8>> DecodeColorImage(std::span<const uint8_t> payload, uint64_t count) {
  if (payload.size() < 3) return Truncated("color image is shorter than its header");
  if (payload[0] > 1 || payload[1] > 2) return Corrupt("color image names an unknown curve or format");
  const auto curve = static_cast<Curve>(payload[0]);
  const auto format = static_cast<ImageFormat>(payload[1]);
  size_t pos = 2;
  uint64_t side = 0;
  if (!GetVarint(payload, pos, side) || count == 0 || side != TextureSide(count) || side * side < count) {
    return Corrupt("color image side does not fit the color count");
  }
  const auto image = payload.subspan(pos);
  RETURN_IF_ERROR(CheckImageBytes(image, format, side));
  ASSIGN_OR_RETURN(const std::vector<uint8_t> pixels, DecodeImageFile(image, format, static_cast<uint32_t>(side)));
  return GatherTexture(pixels, curve, static_cast<uint32_t>(side), 3, count);
}

}  // namespace pointdag
