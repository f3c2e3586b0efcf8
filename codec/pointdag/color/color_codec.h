// Stage 5: the colors section, whichever codec codes it, and the quality knob.
//
// Codecs: "raw" (24 bits), "lossless" (predicted from the voxel's decoded neighbours, context-modelled
// residuals: lossless_context.h; version 1, planar differences in zstd, is still read), the
// block codecs "fixed3" (Paper IIA) and "vbr" (Paper IIB), and the 2D mapping of Paper IIA through
// image codecs: "png" (lossless), "jpeg", "webp", and the GPU texture format "astc". A target
// PSNR-Y makes the encoder predict the block codecs' MSE threshold on a sample, encode once and
// correct macro blocks locally (block_target.h), search the image codecs' quality (bisection on 1..100) or ASTC's footprint (cheapest first), keeping the
// cheapest setting whose decoded colors still meet the target: the target
// is met by measurement, not prediction. The stored section starts with the codec's id byte
// (proto/PDAG_FORMAT.md §3).
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "pointdag/color/color_metrics.h"
#include "pointdag/color/image_mapping.h"
#include "pointdag/status.h"

namespace pointdag {

enum class ColorCodec : uint8_t { kRaw = 0, kLossless = 1, kFixedRate = 2, kVariableRate = 3, kPng = 4, kJpeg = 5, kWebp = 6, kAstc = 7,
                               kHierarchical = 8 };
const char* ColorCodecName(ColorCodec codec);
StatusOr<ColorCodec> ParseColorCodec(const std::string& name);

struct ColorEncodeOptions {
  ColorCodec codec = ColorCodec::kVariableRate;
  std::optional<double> target_psnr_y;  // dB; lossy codecs only
  double max_mse = 16.0;                // per-channel MSE bound of a block when no target is given
  Curve curve = Curve::kHilbert;        // image codecs: the 2D mapping
  int image_quality = 90;               // jpeg/webp when no target is given
  int astc_footprint = 6;               // astc when no target is given
  // Block codecs at a target: a threshold expected near the answer (a sibling tile's), which the
  // encode starts from instead of predicting one on a sample. The target is met either way.
  std::optional<double> threshold_hint = std::nullopt;
  // Block codecs: the stream version to write (block_stream.h); 0: the newest the colors allow
  // (4 with the voxels' Morton codes, else 2). Tiles write 6 (weights read by table lookup).
  uint8_t block_version = 0;
};

bool IsLossy(ColorCodec codec);

struct EncodedColors {
  std::vector<uint8_t> bytes;  // the colors section
  ColorCodec codec = ColorCodec::kRaw;
  double max_mse = 0;          // the threshold used (block codecs; at a target, a typical one)
  ColorPsnr psnr;              // of the decoded colors against the input
  size_t blocks = 0;
  double encodes = 0;          // block codecs at a target: colors encoded, in whole arrays
};

// `morton`: the voxels' Morton codes when `colors` are one per voxel in Morton order (leaf mode),
// else empty; the lossless codec predicts from neighbours found by them, and the block codecs take
// their weights' contexts and endpoint predictions from them (block stream version 4). `judged`: the indices of
// the colors that the target and the reported PSNR are measured on (mipmap mode: the voxels, not
// the internal nodes' colors), each below colors.size(); empty: all of them.
StatusOr<EncodedColors> EncodeColors(std::span<const Rgb8> colors, const ColorEncodeOptions& options,
                                     std::span<const uint64_t> morton = {}, std::span<const uint64_t> judged = {});

// Color indices are 32-bit in the block codec and the DAG's counts: the most a section may hold.
constexpr uint64_t kMaxColors = uint64_t{1} << 32;

// Bit 7 of a colors section's first byte (the codec's number is the other seven): the section of a
// mipmap-mode file holds only the voxels' colors, one per voxel in Morton order, as in leaf mode;
// every internal node's color is derived, not stored: the rounded mean of its children's
// (BuildMipColors over the decoded voxel colors). Coded node colors cost tiles 3-14 % of their
// bytes and their decoders a color per node, for means a client computes when it wants them.
// Leaf-mode sections never set it.
constexpr uint8_t kVoxelColorsOnly = 0x80;

// Decodes a colors section that must hold `count` colors (1..kMaxColors). `count` must come from
// decoded geometry, never from metadata alone: the decoders allocate by it. `morton`: as for
// EncodeColors (a lossless section coded with them cannot be decoded without them).
StatusOr<std::vector<Rgb8>> DecodeColors(std::span<const uint8_t> section, uint64_t count,
                                         std::span<const uint64_t> morton = {});

}  // namespace pointdag
