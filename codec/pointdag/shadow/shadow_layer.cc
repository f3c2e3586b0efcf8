#include "pointdag/shadow/shadow_layer.h"

#include <algorithm>
#include <cstring>
#include <functional>
#include <string>

#include "pointdag/container/crc32c.h"
#include "pointdag/entropy/varint.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

constexpr uint8_t kMagic[4] = {'P', 'D', 'S', 'H'};
// Version 1: runs (value, length - 1). Version 2, written: runs and literal strings (PackBits-like),
// so that neighbours that differ cost about a byte each instead of two. Both are read.
constexpr uint8_t kRunsVersion = 1;
constexpr uint8_t kVersion = 2;
// A run shorter than this goes into the literal string around it: a run token would cost as much.
constexpr size_t kMinRun = 3;

void PutLe(std::vector<uint8_t>& out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

uint64_t GetLe(std::span<const uint8_t> in, size_t at, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t{in[at + static_cast<size_t>(i)]} << (8 * i);
  return v;
}

size_t RunAt(const std::vector<uint8_t>& light, size_t i) {
  size_t j = i + 1;
  while (j < light.size() && light[j] == light[i]) ++j;
  return j - i;
}

// Version 2's body: tokens t (varint); t even: t / 2 + 1 copies of the next byte; t odd: (t - 1) / 2 + 1 bytes follow.
void PutTokens(std::vector<uint8_t>& out, const std::vector<uint8_t>& light) {
  for (size_t i = 0; i < light.size();) {
    const size_t run = RunAt(light, i);
    if (run >= kMinRun) {
      PutVarint(out, (run - 1) << 1);
      out.push_back(light[i]);
      i += run;
      continue;
    }
    size_t j = i;
    while (j < light.size()) {
      const size_t next = RunAt(light, j);
      if (next >= kMinRun) break;
      j += next;
    }
    PutVarint(out, ((j - i - 1) << 1) | 1);
    out.insert(out.end(), light.begin() + static_cast<long>(i), light.begin() + static_cast<long>(j));
    i = j;
  }
}

// Reads version 1's runs or version 2's tokens into `light` until it holds n voxels.
Status ReadBody(std::span<const uint8_t> body, uint8_t version, uint64_t n, std::vector<uint8_t>& light) {
  size_t pos = 0;
  while (light.size() < n) {
    const std::string at = " at voxel " + std::to_string(light.size()) + " of " + std::to_string(n);
    if (pos >= body.size()) return Truncated("the shadow layer ends" + at);
    uint64_t token = 0;
    if (version == kRunsVersion) {
      const uint8_t value = body[pos++];
      if (!GetVarint(body, pos, token)) return Truncated("a run length of the shadow layer is cut short or over 64 bits" + at);
      if (token >= n - light.size()) return Malformed("a run of the shadow layer passes its voxels" + at);
      light.insert(light.end(), token + 1, value);
      continue;
    }
    if (!GetVarint(body, pos, token)) return Truncated("a token of the shadow layer is cut short or over 64 bits" + at);
    const bool literal = token & 1;
    const uint64_t count = (token >> 1) + 1;
    if (count > n - light.size()) return Malformed(std::string(literal ? "a literal string" : "a run") + " of the shadow layer passes its voxels" + at);
    if (!literal) {
      if (pos >= body.size()) return Truncated("the shadow layer ends before a run's value" + at);
      light.insert(light.end(), count, body[pos++]);
    } else {
      if (count > body.size() - pos) return Truncated("the shadow layer ends inside a literal string" + at);
      light.insert(light.end(), body.begin() + static_cast<long>(pos), body.begin() + static_cast<long>(pos + count));
      pos += count;
    }
  }
  if (pos != body.size()) return Malformed(std::to_string(body.size() - pos) + " bytes after the shadow layer's last run");
  return Status::Ok();
}

Status CheckKindAndSamples(ShadowKind kind, int64_t samples) {
  if (kind != ShadowKind::kDirection && kind != ShadowKind::kSunHours) {
    return Malformed("unknown shadow layer kind " + std::to_string(static_cast<int>(kind)));
  }
  if (samples < 1 || samples > kMaxShadowSamples) {
    return Malformed("shadow layer samples " + std::to_string(samples) + " outside 1.." + std::to_string(kMaxShadowSamples));
  }
  if (kind == ShadowKind::kDirection && samples != 1) {
    return Malformed("a one-direction shadow layer has 1 sample, not " + std::to_string(samples));
  }
  return Status::Ok();
}

}  // namespace

uint8_t LightByte(uint64_t lit, uint64_t voxels, int samples) {
  const uint64_t total = voxels * static_cast<uint64_t>(samples);
  return static_cast<uint8_t>((510 * lit + total) / (2 * total));
}

StatusOr<std::vector<uint8_t>> EncodeShadowLayer(const ShadowLayer& layer) {
  if (const Status s = CheckKindAndSamples(layer.kind, layer.samples); !s.ok()) return InvalidArgument(s.message());
  if (layer.light.empty() || layer.light.size() > UINT32_MAX) {
    return InvalidArgument("a shadow layer holds 1 to 2^32 - 1 voxels, not " + std::to_string(layer.light.size()));
  }
  std::vector<uint8_t> out(std::begin(kMagic), std::end(kMagic));
  out.push_back(kVersion);
  out.push_back(static_cast<uint8_t>(layer.kind));
  PutLe(out, static_cast<uint64_t>(layer.samples), 2);
  PutLe(out, layer.light.size(), 4);
  PutLe(out, 0, 4);  // the CRC, once the body is written
  PutTokens(out, layer.light);
  const uint32_t crc = Crc32c(std::span<const uint8_t>(out).subspan(kShadowLayerHeaderBytes));
  for (int i = 0; i < 4; ++i) out[12 + static_cast<size_t>(i)] = static_cast<uint8_t>(crc >> (8 * i));
  return out;
}

StatusOr<ShadowLayer> DecodeShadowLayer(std::span<const uint8_t> bytes, uint64_t tile_voxels) {
  if (bytes.size() < kShadowLayerHeaderBytes) {
    return Truncated("a shadow layer is at least 16 bytes; this one is " + std::to_string(bytes.size()));
  }
  if (std::memcmp(bytes.data(), kMagic, 4) != 0) return Malformed("not a shadow layer (its magic is not PDSH)");
  const uint8_t version = bytes[4];
  if (version != kRunsVersion && version != kVersion) {
    return Malformed("shadow layer version " + std::to_string(version) + "; this reader knows 1 and 2");
  }
  ShadowLayer layer;
  layer.kind = static_cast<ShadowKind>(bytes[5]);
  layer.samples = static_cast<int>(GetLe(bytes, 6, 2));
  RETURN_IF_ERROR(CheckKindAndSamples(layer.kind, layer.samples));
  const uint64_t n = GetLe(bytes, 8, 4);
  if (n != tile_voxels || n == 0) {
    return Malformed("the shadow layer covers " + std::to_string(n) + " voxels; its tile has " + std::to_string(tile_voxels));
  }
  const std::span<const uint8_t> body = bytes.subspan(kShadowLayerHeaderBytes);
  if (Crc32c(body) != static_cast<uint32_t>(GetLe(bytes, 12, 4))) return Corrupt("the shadow layer's CRC-32C does not match its body");
  layer.light.reserve(n);
  RETURN_IF_ERROR(ReadBody(body, version, n, layer.light));
  return layer;
}

StatusOr<std::vector<TileShadowLayer>> ComputeTileLayers(std::span<const uint64_t> finest_morton, int depth,
                                                         std::span<const uint16_t> lit_counts, ShadowKind kind,
                                                         int samples, int tile_depth) {
  if (const Status s = CheckKindAndSamples(kind, samples); !s.ok()) return InvalidArgument(s.message());
  if (finest_morton.size() != lit_counts.size()) {
    return InvalidArgument(std::to_string(lit_counts.size()) + " lit counts for " + std::to_string(finest_morton.size()) + " voxels");
  }
  if (depth < 2 || depth > kMaxDepth || tile_depth < 2) return InvalidArgument("grid depth or tile depth out of range");
  if (std::adjacent_find(finest_morton.begin(), finest_morton.end(), std::greater_equal<>()) != finest_morton.end()) {
    return InvalidArgument("the finest voxels' Morton codes are not sorted and unique");
  }
  if (std::any_of(lit_counts.begin(), lit_counts.end(), [&](uint16_t c) { return c > samples; })) {
    return InvalidArgument("a voxel is lit by more than the " + std::to_string(samples) + " lights");
  }
  const int tile = std::min(tile_depth, depth);
  const int finest_level = depth - tile;
  std::vector<TileShadowLayer> out;
  for (int level = 0; level <= finest_level; ++level) {
    const int shift = 3 * (finest_level - level);
    for (size_t i = 0; i < finest_morton.size();) {
      const uint64_t code = finest_morton[i] >> shift;
      uint64_t lit = 0;
      size_t j = i;
      for (; j < finest_morton.size() && (finest_morton[j] >> shift) == code; ++j) lit += lit_counts[j];
      const uint64_t tile_code = code >> (3 * tile);
      if (out.empty() || out.back().key.level != level || (tile_code != MortonEncode(out.back().key.x, out.back().key.y, out.back().key.z))) {
        const auto [x, y, z] = MortonDecode(tile_code);
        out.push_back({{level, x, y, z}, {kind, samples, {}}});
      }
      out.back().layer.light.push_back(LightByte(lit, j - i, samples));
      i = j;
    }
  }
  std::sort(out.begin(), out.end(), [](const TileShadowLayer& a, const TileShadowLayer& b) { return a.key < b.key; });
  return out;
}

}  // namespace pointdag
