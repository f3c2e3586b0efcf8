// The HTTP API of pointdagd (proto/PROTOCOL.md) as plain functions of a request: no sockets here,
// so every rule — auth, limits, ETag/304, Range/206/416, CORS — lives in one place the transport
// (http_server.cc) merely carries.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "access.h"
#include "jobs.h"
#include "metrics.h"
#include "store.h"
#include "tile_cache.h"
#include "web_files.h"

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

struct ServiceConfig {
  std::string token;       // write scope (uploads, DELETE; reads too); empty: writes need no token
  std::string read_token;  // read scope only (a write with it: 403); empty: none
  bool require_token_for_reads = false;  // GETs of jobs, datasets, tiles, hierarchy, /metrics need the read or write token
  std::vector<std::string> cors_origins{"*"};  // "*" or exact origins echoed back when they match
  uint64_t max_upload_bytes = uint64_t{4} << 30;
  std::filesystem::path upload_dir;
  size_t tile_cache_bytes = size_t{256} << 20;
  std::shared_ptr<const WebFiles> web;  // the viewer's static files; null or empty: no viewer
};

class Service {
 public:
  Service(Store& store, JobQueue& jobs, Metrics& metrics, ServiceConfig config);

  bool IsUpload(const HttpRequest& request) const;
  // Uploads, first from the header alone: an answer (400, 401, 403, 411, 413, 503) or nullopt to read the body.
  std::optional<HttpResponse> AdmitUpload(const HttpRequest& request) const;
  // Then with the body on disk at `file` (removed unless a job takes it).
  HttpResponse FinishUpload(const HttpRequest& request, const std::filesystem::path& file);
  // Every other request.
  HttpResponse Handle(const HttpRequest& request);
  // An error answer in the API's JSON form, with CORS (as for a request without Origin).
  HttpResponse Error(int status, const std::string& message, const std::string& route) const;
  // CORS headers for every answer, for a request from `origin` (empty: none given).
  void AddCors(HttpResponse& response, const std::string& origin = "") const;
  const ServiceConfig& config() const { return config_; }
  void set_ready(bool ready) { ready_ = ready; }

 private:
  // Answers without CORS; the public entry points add it for the request's Origin.
  HttpResponse Json(int status, const nlohmann::json& body, const std::string& route) const;
  HttpResponse Fail(int status, const std::string& message, const std::string& route) const;
  // 503 with Retry-After when another process holds the store's lock, else 500.
  HttpResponse StoreFailure(const Status& status, const std::string& route) const;
  // An answer refusing the request (400, 401, 403), or nullopt when it may go on.
  std::optional<HttpResponse> Deny(const HttpRequest& request, Scope needed, const std::string& route) const;
  HttpResponse Route(const HttpRequest& request);
  std::optional<HttpResponse> Admit(const HttpRequest& request) const;
  HttpResponse Finish(const HttpRequest& request, const std::filesystem::path& file);
  HttpResponse GetJob(const std::string& id);
  // 404 naming what is missing: the dataset, or `what` within it.
  HttpResponse NotFound(const std::string& dataset, const std::string& what, const std::string& route);
  HttpResponse GetTile(const HttpRequest& request, const std::string& dataset, const TileKey& key);
  HttpResponse GetHierarchy(const HttpRequest& request, const std::string& dataset, const TileKey& key);
  static nlohmann::json JobJson(const JobRecord& job);

  Store& store_;
  JobQueue& jobs_;
  Metrics& metrics_;
  ServiceConfig config_;
  AccessPolicy access_;
  CorsPolicy cors_;
  TileCache cache_;
  bool ready_ = false;
};

// Whether an If-None-Match value names `etag` (a list of tags, or exactly "*").
bool EtagMatches(const std::string& if_none_match, const std::string& etag);

// "a=1&b=x%20y" -> {a: 1, b: "x y"}.
std::map<std::string, std::string> ParseQuery(const std::string& query);

}  // namespace pointdag::server
