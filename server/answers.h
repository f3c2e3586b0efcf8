// What every route of the API shares (proto/PROTOCOL.md): the request and response as plain
// values, the JSON answers and error form, and the answer for immutable bytes (tiles, 3D Tiles):
// strong ETag, Cache-Control immutable, If-None-Match -> 304, one Range -> 206 or 416.
// No CORS here: Service adds it to every answer on the way out.
#pragma once

#include <charconv>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "metrics.h"
#include "store.h"

namespace pointdag::server {

struct HttpRequest {
  std::string method;
  std::string target;                          // path and query, as received
  std::map<std::string, std::string> headers;  // names in lower case
  std::string body;                            // small bodies only; uploads go to a file
  std::string Header(const std::string& lower_name) const;
};

struct HttpResponse {
  int status = 200;
  std::vector<std::pair<std::string, std::string>> headers;
  std::string body;
  std::string route;  // the metrics label, e.g. "/v1/datasets/{id}/tiles"
  void SetHeader(const std::string& name, const std::string& value);
};

// `body` as indented JSON, Cache-Control no-store.
HttpResponse JsonAnswer(int status, const nlohmann::json& body, const std::string& route);
// Whether an If-None-Match value names `etag` (a list of tags, or exactly "*").
bool EtagMatches(const std::string& if_none_match, const std::string& etag);
// {"error": message}.
HttpResponse FailAnswer(int status, const std::string& message, const std::string& route);
// 503 with Retry-After when another process holds the store's lock, else 500.
HttpResponse StoreFailureAnswer(const Status& status, const std::string& route);

// 404 naming what is missing: the dataset, or `what` within it (a store failure as above).
HttpResponse NotFoundAnswer(Store& store, const std::string& dataset, const std::string& what, const std::string& route);

// `body` is immutable and `body.etag` its strong ETag: 200, 304 or 206/416 as the request asks.
HttpResponse ImmutableAnswer(const HttpRequest& request, const StoredTile& body, const std::string& content_type,
                             const std::string& route);

// A stored tile whose bytes no longer match their checksum (the ETag) is never served: 500,
// logged and counted. nullopt when the tile is sound.
std::optional<HttpResponse> RefuseCorruptTile(const StoredTile& tile, const std::string& dataset, const std::string& address,
                                              Metrics& metrics, const std::string& route);

// A job as GET /v1/jobs/{id} answers it (proto/PROTOCOL.md §1).
nlohmann::json JobJson(const JobRecord& job);

// The whole of `text` as a number, or nullopt.
template <typename T>
std::optional<T> ParseNumber(const std::string& text) {
  T value{};
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

// parts[first..first+3] = level, x, y, z (level 0..21); nullopt unless exactly those four remain.
std::optional<TileKey> ParseTileKey(const std::vector<std::string>& parts, size_t first);
// "level/x/y/z".
std::string TileAddress(const TileKey& key);

}  // namespace pointdag::server
