// The 2D mapping coded as ASTC (libastcenc), the GPU's own block-compressed texture format: a
// fixed rate per footprint (12x12: 0.89 bits per texel ... 4x4: 8 bits), decoded by texture
// hardware with random access. Blocks that hold only padding texels are not stored: which blocks
// the first N curve positions touch follows from N and the curve.
#pragma once

#include <span>
#include <vector>

#include "pointdag/color/image_mapping.h"

namespace pointdag {

constexpr int kAstcFootprints[] = {12, 10, 8, 6, 5, 4};  // square footprints, cheapest first

// Payload: u8 curve, u8 footprint, varint side, then the stored 16-byte blocks in raster order.
StatusOr<std::vector<uint8_t>> EncodeColorAstc(std::span<const Rgb8> colors, Curve curve, int footprint);
StatusOr<std::vector<Rgb8>> DecodeColorAstc(std::span<const uint8_t> payload, uint64_t count);

}  // namespace pointdag
