// Stage 5d's image files: a square RGB8 texture to PNG, JPEG or WebP bytes and back, in memory,
// each with its format's own library (libpng's simplified API, libjpeg-turbo's TurboJPEG, libwebp).
// They link a handful of shared libraries where a general image library links hundreds, which every
// run of the CLI and the daemon paid for at start-up.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/status.h"

namespace pointdag {

enum class ImageFormat : uint8_t { kPng = 0, kJpeg = 1, kWebp = 2 };
const char* ImageFormatName(ImageFormat format);

// `rgb`: side x side texels, row-major, 3 bytes each. `quality` 1..100 (ignored by PNG). JPEG keeps
// chroma at half resolution (4:2:0) with the accurate integer DCT (the fast one costs up to 1.7 dB
// at quality 100); WebP runs its slowest, smallest method (6).
StatusOr<std::vector<uint8_t>> EncodeImageFile(std::span<const uint8_t> rgb, uint32_t side, ImageFormat format,
                                               int quality);

// The side x side RGB texels of an image file that must be of `format` and exactly that size; any
// other file, or one that fails to decode, is Corrupt. `side` must already be bound by the caller
// (it sizes the output).
StatusOr<std::vector<uint8_t>> DecodeImageFile(std::span<const uint8_t> image, ImageFormat format, uint32_t side);

}  // namespace pointdag
