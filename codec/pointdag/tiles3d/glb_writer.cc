#include "pointdag/tiles3d/glb_writer.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "pointdag/json_text.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

constexpr int kUnsignedShort = 5123, kArrayBuffer = 34962;
constexpr size_t kPositionStride = 8;  // u16 x, y, z and two bytes of padding: attributes align to 4
constexpr size_t kColorStride = 8;     // u16 r, g, b and two bytes of padding

void PutU32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

// EXT_meshopt_compression decoders read vertex codec version 0 only; newer libraries may default
// to another, so it is set once, before the first encode.
void UseVertexCodecVersion0() {
  static const bool kSet = (meshopt_encodeVertexVersion(0), true);
  (void)kSet;
}

struct Stream {
  size_t fallback_offset, stride, count;
  size_t encoded_offset, encoded_length;
};

// Appends `count` vertices of `stride` bytes, meshopt-encoded, to `bin` at a 4-byte boundary.
Stream Encode(std::vector<uint8_t>& bin, const uint8_t* vertices, size_t count, size_t stride, size_t fallback_offset) {
  std::vector<uint8_t> encoded(meshopt_encodeVertexBufferBound(count, stride));
  encoded.resize(meshopt_encodeVertexBuffer(encoded.data(), encoded.size(), vertices, count, stride));
  Stream s{fallback_offset, stride, count, bin.size(), encoded.size()};
  bin.insert(bin.end(), encoded.begin(), encoded.end());
  bin.resize((bin.size() + 3) / 4 * 4, 0);
  return s;
}

nlohmann::json BufferView(const Stream& s) {
  return {{"buffer", 1},
          {"byteOffset", s.fallback_offset},
          {"byteLength", s.count * s.stride},
          {"byteStride", s.stride},
          {"target", kArrayBuffer},
          {"extensions",
           {{"EXT_meshopt_compression",
             {{"buffer", 0},
              {"byteOffset", s.encoded_offset},
              {"byteLength", s.encoded_length},
              {"byteStride", s.stride},
              {"count", s.count},
              {"mode", "ATTRIBUTES"}}}}}};
}

}  // namespace

uint16_t LinearColor16(uint8_t srgb) {
  static const std::array<uint16_t, 256> kTable = [] {
    std::array<uint16_t, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const double c = i / 255.0;  // the sRGB transfer function, inverted (IEC 61966-2-1)
      const double linear = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
      t[i] = static_cast<uint16_t>(std::lround(65535.0 * linear));
    }
    return t;
  }();
  return kTable[srgb];
}

std::array<double, 16> TileNodeMatrix(const std::array<double, 3>& origin, double voxel_size) {
  const double s = voxel_size;
  const double half = 0.5 * s;
  // Columns: cell x -> glTF x, cell y -> glTF -z, cell z -> glTF y; translation of the first
  // voxel's centre. (0.0 - v, not -v: a zero stays +0 and prints as 0.0.)
  return {s, 0, 0, 0,  //
          0, 0, 0.0 - s, 0,
          0, s, 0, 0,
          origin[0] + half, origin[2] + half, 0.0 - (origin[1] + half), 1};
}

StatusOr<std::vector<uint8_t>> WriteTileGlb(const VoxelGrid& tile) {
  const size_t n = tile.morton.size();
  if (n == 0) return InvalidArgument("a tile without voxels has no glTF content");
  if (tile.depth > 16) return InvalidArgument("a tile deeper than 16 levels does not fit unsigned short cells");
  if (tile.has_color() && tile.colors.size() != n) return InvalidArgument("the tile's colors are not one per voxel");
  UseVertexCodecVersion0();

  std::vector<uint16_t> positions(4 * n, 0);
  std::array<uint16_t, 3> lo{}, hi{};
  lo.fill(std::numeric_limits<uint16_t>::max());
  for (size_t i = 0; i < n; ++i) {
    const auto cell = MortonDecode(tile.morton[i]);
    for (int a = 0; a < 3; ++a) {
      const auto c = static_cast<uint16_t>(cell[a]);
      positions[4 * i + a] = c;
      lo[a] = std::min(lo[a], c);
      hi[a] = std::max(hi[a], c);
    }
  }
  // Little-endian in the buffer, as glTF requires.
  std::vector<uint8_t> position_bytes(positions.size() * 2);
  for (size_t i = 0; i < positions.size(); ++i) {
    position_bytes[2 * i] = static_cast<uint8_t>(positions[i]);
    position_bytes[2 * i + 1] = static_cast<uint8_t>(positions[i] >> 8);
  }

  std::vector<uint8_t> bin;
  const Stream position_stream = Encode(bin, position_bytes.data(), n, kPositionStride, 0);
  nlohmann::json accessors = nlohmann::json::array();
  nlohmann::json views = nlohmann::json::array({BufferView(position_stream)});
  accessors.push_back({{"bufferView", 0},
                       {"componentType", kUnsignedShort},
                       {"count", n},
                       {"type", "VEC3"},
                       {"min", lo},
                       {"max", hi}});
  nlohmann::json attributes = {{"POSITION", 0}};
  size_t fallback_bytes = n * kPositionStride;
  if (tile.has_color()) {
    std::vector<uint8_t> colors(kColorStride * n, 0);  // little-endian u16, as glTF requires
    for (size_t i = 0; i < n; ++i) {
      const uint16_t rgb[3] = {LinearColor16(tile.colors[i].r), LinearColor16(tile.colors[i].g), LinearColor16(tile.colors[i].b)};
      for (int c = 0; c < 3; ++c) {
        colors[8 * i + 2 * c] = static_cast<uint8_t>(rgb[c]);
        colors[8 * i + 2 * c + 1] = static_cast<uint8_t>(rgb[c] >> 8);
      }
    }
    views.push_back(BufferView(Encode(bin, colors.data(), n, kColorStride, fallback_bytes)));
    fallback_bytes += n * kColorStride;
    accessors.push_back({{"bufferView", 1}, {"componentType", kUnsignedShort}, {"normalized", true}, {"count", n}, {"type", "VEC3"}});
    attributes["COLOR_0"] = 1;
  }

  const nlohmann::json extensions = {"EXT_meshopt_compression", "KHR_mesh_quantization"};
  const nlohmann::json gltf = {
      {"asset", {{"version", "2.0"}, {"generator", "pointdag"}}},
      {"extensionsUsed", extensions},
      {"extensionsRequired", extensions},
      {"scene", 0},
      {"scenes", {{{"nodes", nlohmann::json::array({0})}}}},
      {"nodes", {{{"mesh", 0}, {"matrix", TileNodeMatrix(tile.origin, tile.voxel_size)}}}},
      {"meshes", {{{"primitives", {{{"attributes", attributes}, {"mode", 0}}}}}}},
      {"accessors", accessors},
      {"bufferViews", views},
      {"buffers",
       {{{"byteLength", bin.size()}},
        {{"byteLength", fallback_bytes}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}}}},
  };
  std::string json = DumpJson(gltf);
  json.resize((json.size() + 3) / 4 * 4, ' ');  // the JSON chunk is padded with spaces

  std::vector<uint8_t> out;
  out.reserve(28 + json.size() + bin.size());
  PutU32(out, 0x46546C67);  // "glTF"
  PutU32(out, 2);
  PutU32(out, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  PutU32(out, static_cast<uint32_t>(json.size()));
  PutU32(out, 0x4E4F534A);  // "JSON"
  out.insert(out.end(), json.begin(), json.end());
  PutU32(out, static_cast<uint32_t>(bin.size()));
  PutU32(out, 0x004E4942);  // "BIN\0"
  out.insert(out.end(), bin.begin(), bin.end());
  return out;
}

}  // namespace pointdag
