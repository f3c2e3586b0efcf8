// 3D Tiles 1.1 for every dataset (proto/PROTOCOL.md §3.1), transcoded from the stored tiles:
//   GET /v1/datasets/{id}/3dtiles/tileset.json          application/json
//   GET /v1/datasets/{id}/3dtiles/{level}/{x}/{y}/{z}.glb model/gltf-binary
//
// Contract: the bytes are those of codec/pointdag/tiles3d (what `pointdag export --3dtiles`
// writes), answered as tiles are (answers.h: strong ETag = XXH3 of the bytes, immutable, 304,
// Range). The tileset needs every tile's tight box, so its first request decodes the geometry of
// every tile of the dataset once; tilesets and contents then stay in an LRU cache of bounded bytes,
// erased with the dataset (the TileCache generation rule: nothing read before a DELETE is put back).
// Method and token checks are the caller's (Service::Route); CORS is added by Service.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include "answers.h"
#include "metrics.h"
#include "store.h"
#include "tile_cache.h"

namespace pointdag::server {

class Tiles3dService {
 public:
  Tiles3dService(Store& store, Metrics& metrics, size_t cache_bytes) : store_(store), metrics_(metrics), cache_(cache_bytes) {}

  // `rest`: the path's parts after ".../3dtiles". 400 for a malformed address, 404 for an unknown
  // dataset or tile, 500 for a tile that fails its checks.
  HttpResponse Get(const HttpRequest& request, const std::string& dataset, const std::vector<std::string>& rest);
  void EraseDataset(const std::string& dataset) { cache_.EraseDataset(dataset); }

 private:
  HttpResponse GetTileset(const HttpRequest& request, const std::string& dataset);
  HttpResponse GetContent(const HttpRequest& request, const std::string& dataset, const TileKey& key);
  // The stored tile, checked against its checksum; an answer when it cannot be had.
  std::variant<StoredTile, HttpResponse> ReadTile(const std::string& dataset, const TileKey& key);

  Store& store_;
  Metrics& metrics_;
  TileCache cache_;  // keys "<dataset>/tileset.json" and "<dataset>/level/x/y/z.glb"
};

}  // namespace pointdag::server
