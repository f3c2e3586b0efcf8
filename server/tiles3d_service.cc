#include "tiles3d_service.h"

#include <chrono>
#include <memory>

#include <spdlog/spdlog.h>

#include "pointdag/tiles3d/tile_content.h"

namespace pointdag::server {
namespace {

const std::string kRoute = "/v1/datasets/{id}/3dtiles";

}  // namespace

HttpResponse Tiles3dService::Get(const HttpRequest& request, const std::string& dataset, const std::vector<std::string>& rest) {
  if (rest.size() == 1 && rest[0] == "tileset.json") return GetTileset(request, dataset);
  if (rest.size() == 4 && rest[3].ends_with(".glb")) {
    std::vector<std::string> parts = rest;
    parts[3].resize(parts[3].size() - 4);
    if (const auto key = ParseTileKey(parts, 0)) return GetContent(request, dataset, *key);
  }
  return FailAnswer(400, "3D Tiles are addressed as 3dtiles/tileset.json and 3dtiles/{level}/{x}/{y}/{z}.glb with level 0..21",
                    kRoute);
}

std::variant<StoredTile, HttpResponse> Tiles3dService::ReadTile(const std::string& dataset, const TileKey& key) {
  const std::string address = TileAddress(key);
  auto stored = store_.GetTile(dataset, key);
  if (!stored.ok()) return StoreFailureAnswer(stored.status(), kRoute);
  if (!*stored) return NotFoundAnswer(store_, dataset, "no tile " + address + " in this dataset", kRoute);
  if (auto corrupt = RefuseCorruptTile(**stored, dataset, address, metrics_, kRoute)) return std::move(*corrupt);
  return std::move(**stored);
}

HttpResponse Tiles3dService::GetTileset(const HttpRequest& request, const std::string& dataset) {
  const std::string cache_key = dataset + "/tileset.json";
  std::shared_ptr<const StoredTile> tileset = cache_.Get(cache_key);
  if (!tileset) {
    const uint64_t generation = cache_.generation();  // before the reads: a DELETE meanwhile keeps it out of the cache
    const auto started = std::chrono::steady_clock::now();
    const auto meta = store_.GetDataset(dataset);
    if (!meta.ok()) return StoreFailureAnswer(meta.status(), kRoute);
    if (!*meta) return FailAnswer(404, "no dataset " + dataset, kRoute);
    const auto shape = ParseTilesetDataset(**meta);
    if (!shape.ok()) return FailAnswer(500, "dataset " + dataset + " has no 3D Tiles: " + shape.status().ToString(), kRoute);
    std::vector<TileKey> unused;
    const auto listed = store_.TilesBelow(dataset, TileKey{}, shape->levels - 1, unused);
    if (!listed.ok()) return StoreFailureAnswer(listed.status(), kRoute);
    std::vector<TileBox> boxes;
    boxes.reserve(listed->size());
    for (const HierarchyEntry& entry : *listed) {
      auto tile = ReadTile(dataset, entry.key);
      if (auto* refused = std::get_if<HttpResponse>(&tile)) return std::move(*refused);
      const auto box = MeasureStoredTile(entry.key, std::get<StoredTile>(tile).bytes, shape->tile_depth);
      if (!box.ok()) {
        return FailAnswer(500, "tile " + TileAddress(entry.key) + " of dataset " + dataset + " does not decode: " +
                                   box.status().ToString(), kRoute);
      }
      boxes.push_back(*box);
    }
    const auto text = BuildTileset(*shape, std::move(boxes));
    if (!text.ok()) return FailAnswer(500, "dataset " + dataset + " has no 3D Tiles: " + text.status().ToString(), kRoute);
    StoredTile built{"", std::vector<uint8_t>(text->begin(), text->end())};
    built.etag = TileEtag(built.bytes);
    spdlog::info("3D Tiles: tileset of dataset {} ({} tiles, {} bytes) built in {:.3f} s", dataset, listed->size(),
                 built.bytes.size(), std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    tileset = std::make_shared<const StoredTile>(std::move(built));
    cache_.Put(cache_key, tileset, generation);
  }
  return ImmutableAnswer(request, *tileset, "application/json", kRoute);
}

HttpResponse Tiles3dService::GetContent(const HttpRequest& request, const std::string& dataset, const TileKey& key) {
  const std::string address = TileAddress(key);
  const std::string cache_key = dataset + "/" + address + ".glb";
  std::shared_ptr<const StoredTile> content = cache_.Get(cache_key);
  if (!content) {
    const uint64_t generation = cache_.generation();
    const auto meta = store_.GetDataset(dataset);
    if (!meta.ok()) return StoreFailureAnswer(meta.status(), kRoute);
    if (!*meta) return FailAnswer(404, "no dataset " + dataset, kRoute);
    const auto shape = ParseTilesetDataset(**meta);
    if (!shape.ok()) return FailAnswer(500, "dataset " + dataset + " has no 3D Tiles: " + shape.status().ToString(), kRoute);
    auto tile = ReadTile(dataset, key);
    if (auto* refused = std::get_if<HttpResponse>(&tile)) return std::move(*refused);
    auto transcoded = TranscodeTile(key, std::get<StoredTile>(tile).bytes, shape->tile_depth);
    if (!transcoded.ok()) {
      return FailAnswer(500, "tile " + address + " of dataset " + dataset + " does not decode: " + transcoded.status().ToString(),
                        kRoute);
    }
    StoredTile built{TileEtag(transcoded->glb), std::move(transcoded->glb)};
    content = std::make_shared<const StoredTile>(std::move(built));
    cache_.Put(cache_key, content, generation);
  }
  return ImmutableAnswer(request, *content, "model/gltf-binary", kRoute);
}

}  // namespace pointdag::server
