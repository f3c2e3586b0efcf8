// Stage 5d: the 2D mapping of Paper IIA. The color array is laid along a space-filling curve
// (Morton or Hilbert) into a square power-of-two texture, so that neighbours in the array stay
// neighbours in the image, and the texture is coded with conventional image codecs
// (image_file.h): PNG (lossless), JPEG and WebP (lossy, with their quality searched for a PSNR-Y
// target). Texels past the last color repeat it, which costs the codecs next to nothing.
// No random access: a reader decodes the whole image.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/color/image_file.h"
#include "pointdag/status.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

enum class Curve : uint8_t { kMorton = 0, kHilbert = 1 };

const char* CurveName(Curve curve);

// Texel (x, y) of position i along the curve on a side x side texture (side a power of two).
std::array<uint32_t, 2> CurvePosition(Curve curve, uint64_t i, uint32_t side);

constexpr uint32_t kMaxTextureSide = uint32_t{1} << 16;  // 2^32 texels: kMaxColors
constexpr uint32_t kMaxLossyTextureSide = 16384;         // WebP's limit

// The smallest power-of-two side whose square holds `count` texels (at most kMaxTextureSide).
uint32_t TextureSide(uint64_t count);
// Colors along the curve into a side x side texture of `channels` 8-bit channels (alpha = 255),
// row-major; texels past the last color repeat it.
std::vector<uint8_t> LayOutTexture(std::span<const Rgb8> colors, Curve curve, uint32_t side, int channels);
// The first `count` colors back out of such a texture.
std::vector<Rgb8> GatherTexture(std::span<const uint8_t> pixels, Curve curve, uint32_t side, int channels, uint64_t count);

// Payload: u8 curve, u8 format, varint side, then the image file's bytes. `quality` 1..100 is
// ignored by PNG.
StatusOr<std::vector<uint8_t>> EncodeColorImage(std::span<const Rgb8> colors, Curve curve, ImageFormat format,
                                                int quality);
StatusOr<std::vector<Rgb8>> DecodeColorImage(std::span<const uint8_t> payload, uint64_t count);

}  // namespace pointdag
