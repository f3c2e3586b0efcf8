#include "pointdag/tiles3d/tileset.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "pointdag/container/json_fields.h"
#include "pointdag/json_text.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag {
namespace {

std::string Address(const TileKey& k) {
  return std::to_string(k.level) + "/" + std::to_string(k.x) + "/" + std::to_string(k.y) + "/" + std::to_string(k.z);
}

}  // namespace

std::string ContentUri(const TileKey& key) { return Address(key) + ".glb"; }

double TilesetDataset::LevelVoxelSize(int level) const { return std::ldexp(voxel_size, levels - 1 - level); }

StatusOr<TilesetDataset> ParseTilesetDataset(const nlohmann::json& dataset) {
  const JsonFields fields(dataset, "the dataset description", StatusCode::kMalformed);
  TilesetDataset out;
  ASSIGN_OR_RETURN(static_cast<TileGridShape&>(out), ReadTileGridShape(fields));
  const nlohmann::json* georeferenced = fields.Find("frame/georeferenced");
  if (georeferenced == nullptr || !georeferenced->is_boolean()) {
    return Malformed("the dataset description's 'frame/georeferenced' is not true or false");
  }
  if (georeferenced->get<bool>()) {
    ASSIGN_OR_RETURN(const nlohmann::json* matrix, fields.Array("frame/enu_to_ecef"));
    if (matrix->size() != 16) return Malformed("the dataset description's 'frame/enu_to_ecef' does not hold 16 numbers");
    std::array<double, 16> m{};
    for (size_t i = 0; i < 16; ++i) {
      const nlohmann::json& v = (*matrix)[i];
      if (!v.is_number() || !std::isfinite(v.get<double>())) {
        return Malformed("the dataset description's 'frame/enu_to_ecef' holds something other than finite numbers");
      }
      m[i] = v.get<double>();
    }
    out.enu_to_ecef = m;
  }
  return out;
}

TileBox MeasureTile(const TileKey& key, std::span<const uint64_t> local_morton, int tile_depth) {
  std::array<uint32_t, 3> lo{UINT32_MAX, UINT32_MAX, UINT32_MAX}, hi{0, 0, 0};
  for (uint64_t code : local_morton) {
    const auto cell = MortonDecode(code);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], cell[a]);
      hi[a] = std::max(hi[a], cell[a]);
    }
  }
  const std::array<uint32_t, 3> base{key.x << tile_depth, key.y << tile_depth, key.z << tile_depth};
  TileBox box{key, {}, {}};
  for (int a = 0; a < 3; ++a) {
    box.min[a] = base[a] + lo[a];
    box.max[a] = base[a] + hi[a];
  }
  return box;
}

std::array<double, 6> BoxInFrame(const TilesetDataset& dataset, const TileBox& box) {
  // From global cells and the exact (power-of-two) level voxel size, so a child's box never pokes
  // out of its parent's by a rounding.
  const double s = dataset.LevelVoxelSize(box.key.level);
  std::array<double, 6> out{};
  for (int a = 0; a < 3; ++a) {
    out[a] = dataset.origin[a] + static_cast<double>(box.min[a]) * s;
    out[3 + a] = dataset.origin[a] + (static_cast<double>(box.max[a]) + 1) * s;
  }
  return out;
}

StatusOr<std::string> BuildTileset(const TilesetDataset& dataset, std::vector<TileBox> tiles) {
  std::sort(tiles.begin(), tiles.end(), [](const TileBox& a, const TileBox& b) { return a.key < b.key; });
  std::map<TileKey, size_t> index;
  std::vector<std::vector<size_t>> children(tiles.size());
  for (size_t i = 0; i < tiles.size(); ++i) {
    const TileKey& k = tiles[i].key;
    const uint64_t side = uint64_t{1} << std::clamp(k.level, 0, 31);
    if (k.level < 0 || k.level >= dataset.levels || k.x >= side || k.y >= side || k.z >= side) {
      return InvalidArgument("tile " + Address(k) + " lies outside the dataset's " + std::to_string(dataset.levels) + " levels");
    }
    if (!index.emplace(k, i).second) return InvalidArgument("tile " + Address(k) + " is listed twice");
    if (k.level == 0) continue;
    const auto parent = index.find(TileKey{k.level - 1, k.x >> 1, k.y >> 1, k.z >> 1});
    if (parent == index.end()) return InvalidArgument("tile " + Address(k) + " has no parent tile");
    children[parent->second].push_back(i);  // in key order, as the tiles are sorted
  }
  if (tiles.empty() || tiles[0].key != TileKey{}) return InvalidArgument("the tiles have no root tile 0/0/0/0");

  const int finest = dataset.levels - 1;
  const auto error_of = [&](int level) { return level == finest ? 0.0 : dataset.LevelVoxelSize(level); };
  // Tiles are at most 21 levels deep: recursion is bounded.
  const auto tile_json = [&](const auto& self, size_t i) -> nlohmann::json {
    const std::array<double, 6> b = BoxInFrame(dataset, tiles[i]);
    std::array<double, 12> box{};
    for (int a = 0; a < 3; ++a) {
      box[a] = 0.5 * (b[a] + b[3 + a]);
      box[3 + 4 * a] = 0.5 * (b[3 + a] - b[a]);  // half axes along x, y, z
    }
    nlohmann::json t = {{"boundingVolume", {{"box", box}}},
                        {"geometricError", error_of(tiles[i].key.level)},
                        {"content", {{"uri", ContentUri(tiles[i].key)}}}};
    if (!children[i].empty()) {
      nlohmann::json list = nlohmann::json::array();
      for (size_t c : children[i]) list.push_back(self(self, c));
      t["children"] = std::move(list);
    }
    return t;
  };
  nlohmann::json root = tile_json(tile_json, 0);
  root["refine"] = "REPLACE";
  root["transform"] = dataset.enu_to_ecef.value_or(std::array<double, 16>{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
  const std::string frame = dataset.enu_to_ecef
                                ? "local ENU metres about the dataset's origin; root.transform takes them to ECEF"
                                : "the scan's own coordinates and units (it has no CRS): root.transform is the identity "
                                  "and the tileset is not placed on the globe";
  const nlohmann::json tileset = {
      {"asset", {{"version", "1.1"}, {"generator", "pointdag"}, {"extras", {{"pointdag", {{"frame", frame}}}}}}},
      {"geometricError", 2 * dataset.LevelVoxelSize(0)},
      {"root", std::move(root)},
  };
  return DumpJson(tileset);
}

}  // namespace pointdag
