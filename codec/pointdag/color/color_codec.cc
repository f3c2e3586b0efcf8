#include "pointdag/color/color_codec.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "pointdag/color/astc_mapping.h"
#include "pointdag/color/block_codec.h"
#include "pointdag/color/block_stream.h"
#include "pointdag/color/block_target.h"
#include "pointdag/color/hierarchical_colors.h"
#include "pointdag/color/lossless_context.h"

namespace pointdag {
namespace {

// PSNR of the decoded colors, over `judged` only when given.
ColorPsnr Measure(std::span<const Rgb8> colors, std::span<const Rgb8> decoded, std::span<const uint64_t> judged) {
  if (judged.empty()) return MeasureColorPsnr(colors, decoded);
  std::vector<Rgb8> a, b;
  a.reserve(judged.size());
  b.reserve(judged.size());
  for (uint64_t i : judged) a.push_back(colors[i]), b.push_back(decoded[i]);
  return MeasureColorPsnr(a, b);
}

BlockLayout LayoutOf(ColorCodec codec) {
  return codec == ColorCodec::kFixedRate ? BlockLayout::kFixedRate : BlockLayout::kVariableRate;
}

// The stored section of `blocks`, measured on the colors it decodes to. The writer rebuilds them as
// it writes (tests check them against BlockColorDecoder's), so the section is not decoded again:
// that decode (Open's entropy decode with its weight contexts) was 12 % of a lion encode at 38 dB.
StatusOr<EncodedColors> SerializeMeasured(std::span<const Rgb8> colors, std::span<const uint64_t> morton,
                                          std::span<const uint64_t> judged, ColorCodec codec,
                                          std::span<const ColorBlock> blocks, double max_mse, uint8_t version,
                                          std::span<const uint8_t> weights = {}) {
  std::vector<Rgb8> decoded;
  ASSIGN_OR_RETURN(std::vector<uint8_t> stream,
                   version ? SerializeBlocksAsVersion(colors, blocks, LayoutOf(codec), version, morton, &decoded, weights)
                           : SerializeBlocks(colors, blocks, LayoutOf(codec), morton, &decoded, weights));
  EncodedColors out;
  out.codec = codec;
  out.max_mse = max_mse;
  out.blocks = blocks.size();
  out.psnr = Measure(colors, decoded, judged);
  out.bytes.push_back(static_cast<uint8_t>(codec));
  out.bytes.insert(out.bytes.end(), stream.begin(), stream.end());
  return out;
}

StatusOr<EncodedColors> EncodeBlocksAt(std::span<const Rgb8> colors, std::span<const uint64_t> morton,
                                       std::span<const uint64_t> judged, ColorCodec codec,
                                       double max_mse, uint8_t version) {
  ASSIGN_OR_RETURN(const std::vector<ColorBlock> blocks, EncodeBlocks(colors, LayoutOf(codec), max_mse));
  return SerializeMeasured(colors, morton, judged, codec, blocks, max_mse, version);
}

// About one encode (block_target.h); the decoded colors are measured again, and should rounding
// put them a hair under the target, the exact encode (threshold 0) is stored instead.
StatusOr<EncodedColors> EncodeBlocksForTarget(std::span<const Rgb8> colors, std::span<const uint64_t> morton,
                                              std::span<const uint64_t> judged, ColorCodec codec,
                                              double target, std::optional<double> hint, uint8_t version) {
  ASSIGN_OR_RETURN(const TargetBlocks found, BlocksForTarget(colors, judged, LayoutOf(codec), target, hint));
  ASSIGN_OR_RETURN(EncodedColors out,
                   SerializeMeasured(colors, morton, judged, codec, found.blocks, found.max_mse, version, found.weights));
  out.encodes = found.encodes;
  if (out.psnr.y >= target) return out;
  ASSIGN_OR_RETURN(out, EncodeBlocksAt(colors, morton, judged, codec, 0, version));
  out.encodes = found.encodes + 1;
  return out;
}

EncodedColors Finish(std::span<const Rgb8> colors, std::span<const uint64_t> judged, ColorCodec codec,
                     std::vector<uint8_t> payload, std::span<const Rgb8> decoded) {
  EncodedColors out;
  out.codec = codec;
  out.psnr = Measure(colors, decoded, judged);
  out.bytes.push_back(static_cast<uint8_t>(codec));
  out.bytes.insert(out.bytes.end(), payload.begin(), payload.end());
  return out;
}

StatusOr<EncodedColors> EncodeImageAt(std::span<const Rgb8> colors, std::span<const uint64_t> judged, ColorCodec codec,
                                      Curve curve, int quality) {
  const ImageFormat format = codec == ColorCodec::kPng ? ImageFormat::kPng
                             : codec == ColorCodec::kJpeg ? ImageFormat::kJpeg
                                                          : ImageFormat::kWebp;
  ASSIGN_OR_RETURN(std::vector<uint8_t> payload, EncodeColorImage(colors, curve, format, quality));
  ASSIGN_OR_RETURN(const std::vector<Rgb8> decoded, DecodeColorImage(payload, colors.size()));
  return Finish(colors, judged, codec, std::move(payload), decoded);
}

// The lowest quality whose decoded colors meet the target (the image codecs' size grows with it).
StatusOr<EncodedColors> SearchImageQuality(std::span<const Rgb8> colors, std::span<const uint64_t> judged,
                                           const ColorEncodeOptions& options) {
  int lo = 1, hi = 100;
  ASSIGN_OR_RETURN(EncodedColors best, EncodeImageAt(colors, judged, options.codec, options.curve, hi));
  if (best.psnr.y < *options.target_psnr_y) {
    return InvalidArgument(std::string(ColorCodecName(options.codec)) + " cannot reach " +
                           std::to_string(*options.target_psnr_y) + " dB PSNR-Y on these colors");
  }
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    ASSIGN_OR_RETURN(EncodedColors trial, EncodeImageAt(colors, judged, options.codec, options.curve, mid));
    if (trial.psnr.y >= *options.target_psnr_y) {
      hi = mid;
      if (trial.bytes.size() <= best.bytes.size()) best = std::move(trial);
    } else {
      lo = mid + 1;
    }
  }
  return best;
}

StatusOr<EncodedColors> EncodeAstcAt(std::span<const Rgb8> colors, std::span<const uint64_t> judged, Curve curve, int footprint) {
  ASSIGN_OR_RETURN(std::vector<uint8_t> payload, EncodeColorAstc(colors, curve, footprint));
  ASSIGN_OR_RETURN(const std::vector<Rgb8> decoded, DecodeColorAstc(payload, colors.size()));
  return Finish(colors, judged, ColorCodec::kAstc, std::move(payload), decoded);
}

// ASTC is fixed-rate per footprint: the first footprint, cheapest first, that meets the target.
StatusOr<EncodedColors> SearchAstcFootprint(std::span<const Rgb8> colors, std::span<const uint64_t> judged,
                                            const ColorEncodeOptions& options) {
  for (int footprint : kAstcFootprints) {
    ASSIGN_OR_RETURN(EncodedColors trial, EncodeAstcAt(colors, judged, options.curve, footprint));
    if (trial.psnr.y >= *options.target_psnr_y) return trial;
  }
  return InvalidArgument("astc cannot reach " + std::to_string(*options.target_psnr_y) + " dB PSNR-Y on these colors");
}

// Leaf mode only: the codec's octree is the voxels' (morton), one color each.
StatusOr<EncodedColors> EncodeHierarchicalAt(std::span<const Rgb8> colors, std::span<const uint64_t> morton,
                                             std::span<const uint64_t> judged, const ColorEncodeOptions& options) {
  if (!judged.empty() || morton.size() != colors.size()) {
    return InvalidArgument("hierarchical colors code one color per voxel (leaf mode), with the voxels' Morton codes");
  }
  HierarchicalColors coded;
  if (options.target_psnr_y) {
    ASSIGN_OR_RETURN(coded, EncodeHierarchicalColorsForTarget(colors, morton, *options.target_psnr_y));
  } else {
    // Without a target, max_mse sets the step as a uniform quantizer's error: MSE = step² / 12.
    const double step16 = 16 * std::sqrt(12 * std::max(options.max_mse, 1e-3));
    const auto to16 = [](double v) { return static_cast<uint16_t>(std::clamp(std::lround(v), 1L, 65535L)); };
    ASSIGN_OR_RETURN(coded, EncodeHierarchicalColors(colors, morton, {to16(step16), to16(1.5 * step16)}));
  }
  EncodedColors out;
  out.codec = ColorCodec::kHierarchical;
  out.psnr = MeasureColorPsnr(colors, coded.decoded);
  out.max_mse = coded.steps.luma / 16.0;
  out.encodes = coded.encodes;
  out.bytes.push_back(static_cast<uint8_t>(ColorCodec::kHierarchical));
  out.bytes.insert(out.bytes.end(), coded.payload.begin(), coded.payload.end());
  return out;
}

}  // namespace

bool IsLossy(ColorCodec codec) {
  return codec == ColorCodec::kFixedRate || codec == ColorCodec::kVariableRate || codec == ColorCodec::kJpeg ||
         codec == ColorCodec::kWebp || codec == ColorCodec::kAstc || codec == ColorCodec::kHierarchical;
}

const char* ColorCodecName(ColorCodec codec) {
  switch (codec) {
    case ColorCodec::kRaw: return "raw";
    case ColorCodec::kLossless: return "lossless";
    case ColorCodec::kFixedRate: return "fixed3";
    case ColorCodec::kVariableRate: return "vbr";
    case ColorCodec::kPng: return "png";
    case ColorCodec::kJpeg: return "jpeg";
    case ColorCodec::kWebp: return "webp";
    case ColorCodec::kAstc: return "astc";
    case ColorCodec::kHierarchical: return "hierarchical";
  }
  return "?";
}

StatusOr<ColorCodec> ParseColorCodec(const std::string& name) {
  for (ColorCodec c : {ColorCodec::kRaw, ColorCodec::kLossless, ColorCodec::kFixedRate, ColorCodec::kVariableRate,
                       ColorCodec::kPng, ColorCodec::kJpeg, ColorCodec::kWebp, ColorCodec::kAstc,
                       ColorCodec::kHierarchical}) {
    if (name == ColorCodecName(c)) return c;
  }
  return InvalidArgument("unknown color codec '" + name + "' (raw, lossless, fixed3, vbr, png, jpeg, webp, astc, hierarchical)");
}

StatusOr<EncodedColors> EncodeColors(std::span<const Rgb8> colors, const ColorEncodeOptions& options,
                                     std::span<const uint64_t> morton, std::span<const uint64_t> judged) {
  if (colors.empty()) return InvalidArgument("no colors to encode");
  for (uint64_t i : judged) {
    if (i >= colors.size()) return InvalidArgument("a judged color index is out of range");
  }
  if (!IsLossy(options.codec) && options.target_psnr_y) {
    return InvalidArgument("a PSNR target needs a lossy codec (vbr, fixed3, jpeg, webp, astc or hierarchical)");
  }
  if (options.codec == ColorCodec::kHierarchical) return EncodeHierarchicalAt(colors, morton, judged, options);
  if (options.codec == ColorCodec::kPng) return EncodeImageAt(colors, judged, options.codec, options.curve, 0);
  if (options.codec == ColorCodec::kAstc) {
    if (!options.target_psnr_y) return EncodeAstcAt(colors, judged, options.curve, options.astc_footprint);
    return SearchAstcFootprint(colors, judged, options);
  }
  if (options.codec == ColorCodec::kJpeg || options.codec == ColorCodec::kWebp) {
    if (!options.target_psnr_y) return EncodeImageAt(colors, judged, options.codec, options.curve, options.image_quality);
    return SearchImageQuality(colors, judged, options);
  }
  if (options.codec == ColorCodec::kRaw || options.codec == ColorCodec::kLossless) {
    EncodedColors out;
    out.codec = options.codec;
    out.psnr = MeasureColorPsnr(colors, colors);
    out.bytes.push_back(static_cast<uint8_t>(options.codec));
    if (options.codec == ColorCodec::kRaw) {
      for (const Rgb8& c : colors) out.bytes.insert(out.bytes.end(), {c.r, c.g, c.b});
    } else {
      ASSIGN_OR_RETURN(const std::vector<uint8_t> payload, EncodeLosslessContext(colors, morton));
      out.bytes.insert(out.bytes.end(), payload.begin(), payload.end());
    }
    return out;
  }
  if (!options.target_psnr_y) return EncodeBlocksAt(colors, morton, judged, options.codec, options.max_mse, options.block_version);

  const double target = *options.target_psnr_y;
  if (!std::isfinite(target) || target <= 0) return InvalidArgument("target PSNR must be a positive number of dB");
  return EncodeBlocksForTarget(colors, morton, judged, options.codec, target, options.threshold_hint, options.block_version);
}

}  // namespace pointdag
