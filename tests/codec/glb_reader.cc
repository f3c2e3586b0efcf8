#include "glb_reader.h"

#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <cstring>
#include <map>
#include <string>

#include "pointdag/tiles3d/glb_writer.h"

namespace pointdag::testing {
namespace {

uint32_t U32(std::span<const uint8_t> b, size_t at) {
  uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// The uncompressed bytes of one attribute, and its accessor.
std::vector<uint8_t> DecodeAttribute(const nlohmann::json& gltf, std::span<const uint8_t> bin, int accessor_index,
                                     size_t expected_stride) {
  const nlohmann::json& accessor = gltf["accessors"][accessor_index];
  const nlohmann::json& view = gltf["bufferViews"][accessor["bufferView"].get<int>()];
  const nlohmann::json& ext = view["extensions"]["EXT_meshopt_compression"];
  const size_t count = accessor["count"], stride = view["byteStride"];
  EXPECT_EQ(stride, expected_stride);
  EXPECT_EQ(view["buffer"], 1);  // the fallback buffer
  EXPECT_EQ(view["byteLength"].get<size_t>(), count * stride);
  EXPECT_EQ(view["byteOffset"].get<size_t>() % 4, 0u);
  EXPECT_LE(view["byteOffset"].get<size_t>() + count * stride, gltf["buffers"][1]["byteLength"].get<size_t>());
  EXPECT_EQ(ext["buffer"], 0);
  EXPECT_EQ(ext["mode"], "ATTRIBUTES");
  EXPECT_FALSE(ext.contains("filter"));
  EXPECT_EQ(ext["count"], count);
  EXPECT_EQ(ext["byteStride"], stride);
  const size_t offset = ext["byteOffset"], length = ext["byteLength"];
  std::vector<uint8_t> out(count * stride);
  if (offset + length > bin.size()) {
    ADD_FAILURE() << "a meshopt stream lies outside the BIN chunk";
    return out;
  }
  EXPECT_EQ(meshopt_decodeVertexBuffer(out.data(), count, stride, bin.data() + offset, length), 0);
  return out;
}

}  // namespace

GlbPoints ReadGlb(std::span<const uint8_t> glb) {
  GlbPoints out;
  if (glb.size() < 28) {
    ADD_FAILURE() << "a .glb of " << glb.size() << " bytes";
    return out;
  }
  EXPECT_EQ(U32(glb, 0), 0x46546C67u);  // "glTF"
  EXPECT_EQ(U32(glb, 4), 2u);
  EXPECT_EQ(U32(glb, 8), glb.size());
  const uint32_t json_length = U32(glb, 12);
  EXPECT_EQ(U32(glb, 16), 0x4E4F534Au);  // "JSON"
  EXPECT_EQ(json_length % 4, 0u);
  if (20 + size_t{json_length} + 8 > glb.size()) {
    ADD_FAILURE() << "the JSON chunk overruns the file";
    return out;
  }
  out.gltf = nlohmann::json::parse(std::string(glb.begin() + 20, glb.begin() + 20 + json_length));
  const size_t bin_at = 20 + json_length;
  const uint32_t bin_length = U32(glb, bin_at);
  EXPECT_EQ(U32(glb, bin_at + 4), 0x004E4942u);  // "BIN\0"
  EXPECT_EQ(bin_at + 8 + bin_length, glb.size());
  const std::span<const uint8_t> bin = glb.subspan(bin_at + 8, std::min<size_t>(bin_length, glb.size() - bin_at - 8));

  const nlohmann::json& g = out.gltf;
  EXPECT_EQ(g["asset"]["version"], "2.0");
  for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
    EXPECT_EQ(g[list], nlohmann::json({"EXT_meshopt_compression", "KHR_mesh_quantization"})) << list;
  }
  EXPECT_FALSE(g["buffers"][0].contains("uri"));
  EXPECT_EQ(g["buffers"][0]["byteLength"], bin_length);
  EXPECT_FALSE(g["buffers"][1].contains("uri"));
  EXPECT_EQ(g["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"], true);
  EXPECT_EQ(g["scenes"][g["scene"].get<int>()]["nodes"], nlohmann::json::array({0}));
  EXPECT_EQ(g["nodes"].size(), 1u);
  EXPECT_EQ(g["meshes"].size(), 1u);
  EXPECT_EQ(g["meshes"][0]["primitives"].size(), 1u);
  const nlohmann::json& primitive = g["meshes"][0]["primitives"][0];
  EXPECT_EQ(primitive["mode"], 0);
  EXPECT_FALSE(primitive.contains("indices"));

  const int position_index = primitive["attributes"]["POSITION"];
  const nlohmann::json& position = g["accessors"][position_index];
  EXPECT_EQ(position["componentType"], 5123);
  EXPECT_EQ(position["type"], "VEC3");
  EXPECT_FALSE(position.value("normalized", false));
  const size_t count = position["count"];
  const std::vector<uint8_t> cells = DecodeAttribute(g, bin, position_index, 8);
  const auto matrix = g["nodes"][0]["matrix"].get<std::array<double, 16>>();
  std::array<uint16_t, 3> lo{65535, 65535, 65535}, hi{0, 0, 0};
  for (size_t i = 0; i < count; ++i) {
    std::array<uint16_t, 4> c{};
    std::memcpy(c.data(), cells.data() + 8 * i, 8);
    out.padding_zero = out.padding_zero && c[3] == 0;
    out.cells.push_back({c[0], c[1], c[2]});
    std::array<double, 3> gl{};
    for (int r = 0; r < 3; ++r) gl[r] = matrix[r] * c[0] + matrix[4 + r] * c[1] + matrix[8 + r] * c[2] + matrix[12 + r];
    out.positions.push_back({gl[0], -gl[2], gl[1]});
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
  }
  EXPECT_EQ(position["min"], nlohmann::json(lo));
  EXPECT_EQ(position["max"], nlohmann::json(hi));

  if (primitive["attributes"].contains("COLOR_0")) {
    const int color_index = primitive["attributes"]["COLOR_0"];
    const nlohmann::json& color = g["accessors"][color_index];
    EXPECT_EQ(color["componentType"], 5123);
    EXPECT_EQ(color["type"], "VEC3");
    EXPECT_EQ(color["normalized"], true);
    EXPECT_EQ(color["count"], count);
    const std::vector<uint8_t> rgb = DecodeAttribute(g, bin, color_index, 8);
    // Linear 16-bit colors back to the sRGB bytes they came from: each must be one of LinearColor16's.
    std::map<uint16_t, uint8_t> srgb_of;
    for (int v = 0; v < 256; ++v) srgb_of[LinearColor16(static_cast<uint8_t>(v))] = static_cast<uint8_t>(v);
    EXPECT_EQ(srgb_of.size(), 256u);  // one linear value per byte: the bytes come back exactly
    for (size_t i = 0; i < count; ++i) {
      std::array<uint16_t, 4> c{};
      std::memcpy(c.data(), rgb.data() + 8 * i, 8);
      std::array<uint8_t, 3> back{};
      for (int k = 0; k < 3; ++k) {
        const auto it = srgb_of.find(c[k]);
        EXPECT_NE(it, srgb_of.end()) << "COLOR_0 " << c[k] << " is no sRGB byte's linear value";
        back[k] = it == srgb_of.end() ? 0 : it->second;
      }
      out.colors.push_back({back[0], back[1], back[2]});
      out.padding_zero = out.padding_zero && c[3] == 0;
    }
  }
  return out;
}

}  // namespace pointdag::testing
