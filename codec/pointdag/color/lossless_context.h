// The lossless colors' context-modelled coder (colors section codec 1, versions 2 to 4;
// proto/PDAG_FORMAT.md §3). Colors are coded in their order, each predicted from colors already coded:
//  - with the voxels' Morton codes ("neighbour" mode), from the voxel's face, edge and corner
//    neighbours that precede it in Morton order (x-1, y-1, z-1 always do), found by code, weighted
//    by nearness (two weightings; the one that missed less on the adjacent voxels predicts); with
//    none within 2 voxels, from those within 4; with none at all, from the previous voxel;
//  - without them (mipmap colors, whose order is not the voxels'), from the previous color.
// G is predicted first; R and B as G plus the neighbours' mean R-G and B-G plus a running
// least-squares share of G's residual, so the error they share with G is not paid twice. In version
// 2 each residual is a zigzag gamma code on the adaptive binary range coder, its models chosen by
// how much the neighbours disagree (and, for R and B, by G's residual): flat areas and edges learn
// separate statistics. Version 3 (lossless_mixing.h, what the encoder writes) mixes several such
// contexts per binary decision and reaches further for sparse voxels; version 4 (lossless_transform.h)
// lets the encoder choose which channel leads and whether the columns around a voxel, at any
// height, predict it too (airborne scans).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "pointdag/status.h"
#include "pointdag/voxelize/voxelizer.h"

namespace pointdag {

constexpr int kLosslessContextVersion = 4;

// `morton`: empty (previous-color mode) or one code per color, sorted and unique (neighbour mode).
// The payload after the codec byte: version, mode, count, (version 4) layout, range-coded
// residuals. `version` 2 or 3 only to test that older files still decode; `layout` (version 4,
// lossless_transform.h) only to test each one: the encoder chooses it.
StatusOr<std::vector<uint8_t>> EncodeLosslessContext(std::span<const Rgb8> colors, std::span<const uint64_t> morton,
                                                     int version = kLosslessContextVersion,
                                                     std::optional<uint8_t> layout = std::nullopt);

// True when `payload` is this coder's (version 2 or 3), not the zstd planes of version 1.
bool IsLosslessContextPayload(std::span<const uint8_t> payload);

// `count` from the decoded geometry; a neighbour-mode payload needs `morton` with `count` codes
// (sorted and unique, as the geometry enumerates them) and is kCorrupt without them (mipmap colors,
// for which the encoder writes previous-color mode).
StatusOr<std::vector<Rgb8>> DecodeLosslessContext(std::span<const uint8_t> payload, uint64_t count,
                                                  std::span<const uint64_t> morton);

}  // namespace pointdag
