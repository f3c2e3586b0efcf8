// The color-section fuzz targets' input: a decoder needs the voxel count that the geometry gives
// it, so the first 3 bytes are that count (little-endian, at most 2^24 - 1, as a tile's voxels);
// the rest is the section's payload, after the codec byte that the target fixes. With `morton`, the
// voxels are the first `count` Morton codes (a dense block, every neighbour present) when there are
// at most 2^16 of them, as geometry would give them; none above, which such a section must refuse.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "pointdag/color/color_codec.h"

namespace pointdag::fuzz {

inline void DecodeColorSection(pointdag::ColorCodec codec, const uint8_t* data, size_t size, bool morton = false) {
  if (size < 3) return;
  const uint64_t count = uint64_t{data[0]} | uint64_t{data[1]} << 8 | uint64_t{data[2]} << 16;
  std::vector<uint8_t> section = {static_cast<uint8_t>(codec)};
  section.insert(section.end(), data + 3, data + size);
  std::vector<uint64_t> codes;
  if (morton && count <= (uint64_t{1} << 16)) {
    codes.resize(count);
    for (uint64_t i = 0; i < count; ++i) codes[i] = i;
  }
  (void)pointdag::DecodeColors(section, count, codes);
}

}  // namespace pointdag::fuzz
