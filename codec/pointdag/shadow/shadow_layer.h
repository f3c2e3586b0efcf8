// Stage 10c (issue #16): the per-tile shadow layer that pointdagd serves beside each LOD tile
// (proto/SHADOW_FORMAT.md §2): one byte of light per voxel of the tile, in the tile's Morton order.
//
// Contract: light = round(255 · lit fraction), the fraction of a finest voxel being (lights that
// light it) / (lights) and of a coarser voxel the mean over the finest voxels it covers, so a coarse
// byte is the mean of the fine ones *before* rounding (ties round up: (510·lit + n·s) / (2·n·s)).
// Written as version 2 (runs and literal strings); version 1 (runs only) is read too.
// The decoder takes hostile bytes: every violation of §2 is a typed Status (kMalformed for the
// format's own rules, kCorrupt for a CRC mismatch, kTruncated for bytes that end too soon), memory
// is bounded by the caller's voxel count, never by the header.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pointdag/status.h"
#include "pointdag/tile/tiler.h"

namespace pointdag {

enum class ShadowKind : uint8_t {
  kDirection = 0,  // one light (a direction, or the sun at one time): samples == 1
  kSunHours = 1,   // several times of a day: samples in 1..kMaxShadowSamples
};
constexpr int kMaxShadowSamples = 1440;  // one a minute over a day
constexpr size_t kShadowLayerHeaderBytes = 16;

struct ShadowLayer {
  ShadowKind kind = ShadowKind::kDirection;
  int samples = 1;
  std::vector<uint8_t> light;  // one byte per voxel of the tile, Morton order
};

// kInvalidArgument for a layer §2 cannot hold (no voxels, more than 2^32 - 1, samples out of range
// or not 1 for kDirection).
StatusOr<std::vector<uint8_t>> EncodeShadowLayer(const ShadowLayer& layer);

// `tile_voxels`: the voxel count of the tile the layer belongs to (from its hierarchy entry or its
// decoded geometry); a layer declaring another count is refused before anything is allocated.
StatusOr<ShadowLayer> DecodeShadowLayer(std::span<const uint8_t> bytes, uint64_t tile_voxels);

// round(255 · lit / (voxels · samples)), exactly, ties up. voxels · samples < 2^54 (a dataset's
// voxels fit in memory: far fewer).
uint8_t LightByte(uint64_t lit, uint64_t voxels, int samples);

struct TileShadowLayer {
  TileKey key;
  ShadowLayer layer;
};

// Every tile's layer of a dataset, as tiler.h cuts the tiles (levels 0..depth - T, T = min(tile_depth,
// depth)), sorted by key. `finest_morton`: the finest voxels (sorted, unique, codes of `depth` levels);
// `lit_counts`: per voxel, how many of `samples` lights light it (voxel_shadows.h, same order).
// kInvalidArgument when the sizes differ, a count exceeds `samples`, or the inputs are out of range.
StatusOr<std::vector<TileShadowLayer>> ComputeTileLayers(std::span<const uint64_t> finest_morton, int depth,
                                                         std::span<const uint16_t> lit_counts, ShadowKind kind,
                                                         int samples, int tile_depth);

}  // namespace pointdag
