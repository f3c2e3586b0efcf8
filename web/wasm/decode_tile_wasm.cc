// The C++ tile decoder (codec/pointdag: container, DAG stream, block colors, mip colors,
// DecodePdag) behind a C ABI for WebAssembly, for the web viewer's worker
// (web/src/decoder/wasm_decoder.js reads the result through these functions).
//
// The WebAssembly build has no zstd, image libraries or astcenc: tiles never use them (their geometry
// is context-coded, their colors VBR), and a .pdag that would need them is refused as Unsupported
// right after its container is checked, before anything else is decoded (as the JavaScript decoder
// does, web/src/decoder/decode_pdag.js refuseUnsupported). The stand-ins that let the real sources
// link (stand_in/zstd.h, unsupported_in_wasm.cc) are therefore never reached.
#include <emscripten/emscripten.h>

#include <cstdint>
#include <cstdlib>
#include <limits>
#include <new>
#include <span>
#include <string>
#include <vector>

#include "pointdag/color/color_codec.h"
#include "pointdag/dag/spatial_coder.h"
#include "pointdag/json_text.h"
#include "pointdag/pipeline.h"
#include "pointdag/voxelize/morton.h"

namespace {

using pointdag::StatusCode;

// The error codes of web/src/decoder/pdag_error.js.
enum ResultCode : int32_t { kOk = 0, kCorrupt = 1, kResourceLimit = 2, kUnsupported = 3 };

struct Result {
  ResultCode code = kOk;
  std::string message;
  std::string meta;  // the metadata as JSON text
  int32_t depth = 0;
  double voxel_size = 0;
  double origin[3] = {0, 0, 0};
  uint32_t count = 0;
  std::vector<uint16_t> coords16;  // depth <= 16
  std::vector<uint32_t> coords32;  // depth > 16
  std::vector<pointdag::Rgb8> colors;
};

ResultCode CodeOf(StatusCode code) {
  switch (code) {
    case StatusCode::kResourceLimit: return kResourceLimit;
    case StatusCode::kUnsupported: return kUnsupported;
    default: return kCorrupt;  // kCorrupt, kTruncated, kMalformed: the bytes are wrong
  }
}

Result* Fail(Result* r, const pointdag::Status& status) {
  r->code = CodeOf(status.code());
  // The JS side prefixes the code; a C++ code that maps onto another (kTruncated) keeps its name.
  const bool same = status.code() == StatusCode::kCorrupt || status.code() == StatusCode::kResourceLimit ||
                    status.code() == StatusCode::kUnsupported;
  r->message = same ? status.message() : status.ToString();
  return r;
}

pointdag::Status RefuseUnsupported(const pointdag::PdagFile& file) {
  // (Version 8's second byte is its depth and mode, not a coder.)
  if (file.geometry.size() >= 2 && file.geometry[0] != pointdag::kCompactSpatialVersion &&
      file.geometry[1] == static_cast<uint8_t>(pointdag::GeometryCoder::kZstd)) {
    return pointdag::Unsupported("the geometry stream is zstd-coded; this decoder reads the range coders only");
  }
  if (file.colors.empty()) return pointdag::Status::Ok();
  const uint8_t codec = file.colors[0] & ~pointdag::kVoxelColorsOnly;
  switch (static_cast<pointdag::ColorCodec>(codec)) {
    case pointdag::ColorCodec::kLossless: return pointdag::Unsupported("lossless (zstd) colors are not read by this decoder");
    case pointdag::ColorCodec::kPng:
    case pointdag::ColorCodec::kJpeg:
    case pointdag::ColorCodec::kWebp:
    case pointdag::ColorCodec::kAstc:
      return pointdag::Unsupported("image-mapped colors (codec " + std::to_string(codec) +
                                   ": png, jpeg, webp or astc) are not read by this decoder");
    case pointdag::ColorCodec::kHierarchical:
      return pointdag::Unsupported("hierarchical colors (codec 8) are not read by this decoder");
    default: return pointdag::Status::Ok();
  }
}

template <typename T>
void WriteCoords(const std::vector<uint64_t>& morton, std::vector<T>& out) {
  out.resize(3 * morton.size());
  for (size_t i = 0; i < morton.size(); ++i) {
    const auto cell = pointdag::MortonDecode(morton[i]);
    for (int a = 0; a < 3; ++a) out[3 * i + a] = static_cast<T>(cell[a]);
  }
}

}  // namespace

extern "C" {

// Decodes bytes[0, size) under the given limits (DecodeLimits). Never returns null; free the
// result with pdag_result_free.
EMSCRIPTEN_KEEPALIVE Result* pdag_decode(const uint8_t* bytes, uint32_t size, double max_voxels, double max_nodes) {
  auto* r = new Result;
  auto file = pointdag::ParsePdag(std::span<const uint8_t>(bytes, size));
  if (!file.ok()) return Fail(r, file.status());
  if (pointdag::Status s = RefuseUnsupported(*file); !s.ok()) return Fail(r, s);
  pointdag::DecodeLimits limits;
  limits.max_voxels = static_cast<uint64_t>(max_voxels);
  limits.max_nodes = static_cast<uint64_t>(max_nodes);
  auto decoded = pointdag::DecodePdag(*file, limits);
  if (!decoded.ok()) return Fail(r, decoded.status());
  const pointdag::VoxelGrid& grid = decoded->grid;
  r->meta = pointdag::DumpJson(file->meta);
  r->depth = grid.depth;
  r->voxel_size = grid.voxel_size;
  for (int a = 0; a < 3; ++a) r->origin[a] = grid.origin[a];
  r->count = static_cast<uint32_t>(grid.morton.size());
  if (grid.depth > 16) WriteCoords(grid.morton, r->coords32);
  else WriteCoords(grid.morton, r->coords16);
  r->colors = std::move(decoded->grid.colors);
  return r;
}

EMSCRIPTEN_KEEPALIVE void pdag_result_free(Result* r) { delete r; }
EMSCRIPTEN_KEEPALIVE int32_t pdag_result_code(const Result* r) { return r->code; }
EMSCRIPTEN_KEEPALIVE const char* pdag_result_message(const Result* r) { return r->message.data(); }
EMSCRIPTEN_KEEPALIVE uint32_t pdag_result_message_length(const Result* r) { return static_cast<uint32_t>(r->message.size()); }
EMSCRIPTEN_KEEPALIVE const char* pdag_result_meta(const Result* r) { return r->meta.data(); }
EMSCRIPTEN_KEEPALIVE uint32_t pdag_result_meta_length(const Result* r) { return static_cast<uint32_t>(r->meta.size()); }
EMSCRIPTEN_KEEPALIVE int32_t pdag_result_depth(const Result* r) { return r->depth; }
EMSCRIPTEN_KEEPALIVE double pdag_result_voxel_size(const Result* r) { return r->voxel_size; }
EMSCRIPTEN_KEEPALIVE double pdag_result_origin(const Result* r, int32_t axis) { return r->origin[axis]; }
EMSCRIPTEN_KEEPALIVE uint32_t pdag_result_count(const Result* r) { return r->count; }
// 3 * count coordinates: uint16 when depth <= 16, else uint32.
EMSCRIPTEN_KEEPALIVE const void* pdag_result_coords(const Result* r) {
  return r->depth > 16 ? static_cast<const void*>(r->coords32.data()) : static_cast<const void*>(r->coords16.data());
}
// 3 * count bytes, or null when the tile has no colors.
EMSCRIPTEN_KEEPALIVE const uint8_t* pdag_result_colors(const Result* r) {
  static_assert(sizeof(pointdag::Rgb8) == 3);
  return r->colors.empty() ? nullptr : reinterpret_cast<const uint8_t*>(r->colors.data());
}

}  // extern "C"
