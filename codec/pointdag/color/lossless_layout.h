// Version 4's encoder (lossless_transform.h): version 3's coder on the colors in a layout's channel
// order, with the layout the encoder chooses by coding a sample in several.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/color/lossless_transform.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag::lossless {

// The range-coded colors in `layout`. `morton`: empty (previous-color mode) or one code per color,
// sorted and unique.
std::vector<uint8_t> EncodeLaid(std::span<const Rgb8> colors, std::span<const uint64_t> morton, Layout layout);

struct LaidOut {
  Layout layout;
  std::vector<uint8_t> coded;  // EncodeLaid(colors, morton, layout)
};

// The layout that codes the first colors smallest, and the colors coded in it. Their bytes are
// what they would be in the whole stream (each color is coded from earlier ones only), and the
// first eighth (at least 16384) of the Morton order is a region of the scan large enough to tell an
// airborne scan's columns from a close-up's. Column mode first (order 0), then the channel order
// with it.
LaidOut EncodeChosenLayout(std::span<const Rgb8> colors, std::span<const uint64_t> morton);

}  // namespace pointdag::lossless
