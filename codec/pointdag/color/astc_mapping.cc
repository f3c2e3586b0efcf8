#include "pointdag/color/astc_mapping.h"

#include <astcenc.h>

#include <algorithm>
#include <memory>
#include <string>

#include "pointdag/entropy/varint.h"

namespace pointdag {
namespace {

constexpr size_t kBlockBytes = 16;

bool ValidFootprint(int footprint) {
  return std::find(std::begin(kAstcFootprints), std::end(kAstcFootprints), footprint) != std::end(kAstcFootprints);
}

struct Context {
  astcenc_context* ctx = nullptr;
  ~Context() {
    if (ctx) astcenc_context_free(ctx);
  }
};

Status MakeContext(int footprint, Context& context) {
  astcenc_config config;
  const auto fp = static_cast<unsigned>(footprint);
  if (astcenc_config_init(ASTCENC_PRF_LDR, fp, fp, 1, ASTCENC_PRE_MEDIUM, 0, &config) != ASTCENC_SUCCESS ||
      astcenc_context_alloc(&config, 1, &context.ctx) != ASTCENC_SUCCESS) {
    return Internal("astcenc refused a " + std::to_string(footprint) + "x" + std::to_string(footprint) + " footprint");
  }
  return Status::Ok();
}

// Which blocks (raster order) hold at least one of the first `count` curve positions.
std::vector<bool> UsedBlocks(Curve curve, uint32_t side, int footprint, uint64_t count) {
  const uint32_t blocks_x = (side + static_cast<uint32_t>(footprint) - 1) / static_cast<uint32_t>(footprint);
  std::vector<bool> used(size_t{blocks_x} * blocks_x, false);
  for (uint64_t i = 0; i < count; ++i) {
    const auto [x, y] = CurvePosition(curve, i, side);
    used[size_t{y / static_cast<uint32_t>(footprint)} * blocks_x + x / static_cast<uint32_t>(footprint)] = true;
  }
  return used;
}

constexpr astcenc_swizzle kRgba = {ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_A};

}  // namespace

StatusOr<std::vector<uint8_t>> EncodeColorAstc(std::span<const Rgb8> colors, Curve curve, int footprint) {
  if (colors.empty()) return InvalidArgument("no colors to map");
  if (!ValidFootprint(footprint)) return InvalidArgument("unsupported ASTC footprint");
  const uint32_t side = TextureSide(colors.size());
  std::vector<uint8_t> pixels = LayOutTexture(colors, curve, side, 4);
  void* slices[] = {pixels.data()};
  astcenc_image image{side, side, 1, ASTCENC_TYPE_U8, slices};
  Context context;
  RETURN_IF_ERROR(MakeContext(footprint, context));
  const uint32_t blocks_x = (side + static_cast<uint32_t>(footprint) - 1) / static_cast<uint32_t>(footprint);
  std::vector<uint8_t> blocks(size_t{blocks_x} * blocks_x * kBlockBytes);
  if (astcenc_compress_image(context.ctx, &image, &kRgba, blocks.data(), blocks.size(), 0) != ASTCENC_SUCCESS) {
    return Internal("astcenc failed to compress the color texture");
  }
  std::vector<uint8_t> payload = {static_cast<uint8_t>(curve), static_cast<uint8_t>(footprint)};
  PutVarint(payload, side);
  const auto used = UsedBlocks(curve, side, footprint, colors.size());
  for (size_t b = 0; b < used.size(); ++b) {
    if (used[b]) payload.insert(payload.end(), blocks.begin() + static_cast<long>(b * kBlockBytes),
                                blocks.begin() + static_cast<long>((b + 1) * kBlockBytes));
  }
  return payload;
}

StatusOr<std::vector<Rgb8>> DecodeColorAstc(std::span<const uint8_t> payload, uint64_t count) {
  if (payload.size() < 3) return Truncated("ASTC colors are shorter than their header");
  const int footprint = payload[1];
  if (payload[0] > 1 || !ValidFootprint(footprint)) return Corrupt("ASTC colors name an unknown curve or footprint");
  const auto curve = static_cast<Curve>(payload[0]);
  size_t pos = 2;
  uint64_t side = 0;
  if (!GetVarint(payload, pos, side) || count == 0 || side != TextureSide(count) || side * side < count) {
    return Corrupt("ASTC texture side does not fit the color count");
  }
  // Every color lies in a stored block: the blocks bound the count before anything is allocated.
  const uint64_t texels_per_block = static_cast<uint64_t>(footprint) * static_cast<uint64_t>(footprint);
  if (count > (payload.size() - pos) / kBlockBytes * texels_per_block) return Corrupt("ASTC colors hold too few blocks");
  const auto used = UsedBlocks(curve, static_cast<uint32_t>(side), footprint, count);
  const size_t stored = static_cast<size_t>(std::count(used.begin(), used.end(), true));
  if (payload.size() - pos != stored * kBlockBytes) return Corrupt("ASTC colors hold the wrong number of blocks");
  // Unstored blocks only cover padding; any valid block will do there, so repeat the first.
  std::vector<uint8_t> blocks(used.size() * kBlockBytes);
  for (size_t b = 0, next = pos; b < used.size(); ++b) {
    const size_t from = used[b] ? next : pos;
    std::copy_n(payload.begin() + static_cast<long>(from), kBlockBytes, blocks.begin() + static_cast<long>(b * kBlockBytes));
    if (used[b]) next += kBlockBytes;
  }
  Context context;
  RETURN_IF_ERROR(MakeContext(footprint, context));
  std::vector<uint8_t> pixels(side * side * 4);
  void* slices[] = {pixels.data()};
  astcenc_image image{static_cast<unsigned>(side), static_cast<unsigned>(side), 1, ASTCENC_TYPE_U8, slices};
  if (astcenc_decompress_image(context.ctx, blocks.data(), blocks.size(), &image, &kRgba, 0) != ASTCENC_SUCCESS) {
    return Corrupt("ASTC colors fail to decode");
  }
  return GatherTexture(pixels, curve, static_cast<uint32_t>(side), 4, count);
}

}  // namespace pointdag
