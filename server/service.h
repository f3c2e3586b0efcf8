// The HTTP API of pointdagd (proto/PROTOCOL.md) as plain functions of a request: no sockets here,
// so every rule — auth, limits, ETag/304, Range/206/416 (answers.h), CORS — lives in one place the
// transport (http_server.cc) merely carries. The 3D Tiles routes are tiles3d_service.h's, the
// shadow routes shadow_service.h's.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "access.h"
#include "answers.h"
#include "jobs.h"
#include "metrics.h"
#include "reports_service.h"
#include "shadow_service.h"
#include "store.h"
#include "tile_cache.h"
#include "tiles3d_service.h"
#include "web_files.h"

namespace pointdag::server {

struct ServiceConfig {
  std::string token;       // write scope (uploads, DELETE; reads too); empty: writes need no token
  std::string read_token;  // read scope only (a write with it: 403); empty: none
  bool require_token_for_reads = false;  // GETs of jobs, datasets, tiles, hierarchy, /metrics need the read or write token
  std::vector<std::string> cors_origins{"*"};  // "*" or exact origins echoed back when they match
  uint64_t max_upload_bytes = uint64_t{4} << 30;
  std::filesystem::path upload_dir;
  size_t tile_cache_bytes = size_t{256} << 20;
  std::shared_ptr<const WebFiles> web;  // the viewer's static files; null or empty: no viewer
  size_t tiles3d_cache_bytes = size_t{256} << 20;  // transcoded 3D Tiles contents and tilesets
  std::filesystem::path reports_dir;  // the nightly benchmark's reports (reports_service.h)
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
  // Answers are built without CORS (answers.h); the public entry points add it for the request's Origin.
  // An answer refusing the request (400, 401, 403), or nullopt when it may go on.
  std::optional<HttpResponse> Deny(const HttpRequest& request, Scope needed, const std::string& route) const;
  HttpResponse Route(const HttpRequest& request);
  std::optional<HttpResponse> Admit(const HttpRequest& request) const;
  HttpResponse Finish(const HttpRequest& request, const std::filesystem::path& file);
  HttpResponse GetJob(const std::string& id);
  HttpResponse RouteShadows(const HttpRequest& request, const std::string& id, const std::vector<std::string>& parts);
  HttpResponse GetTile(const HttpRequest& request, const std::string& dataset, const TileKey& key);
  HttpResponse GetHierarchy(const HttpRequest& request, const std::string& dataset, const TileKey& key);

  Store& store_;
  JobQueue& jobs_;
  Metrics& metrics_;
  ServiceConfig config_;
  AccessPolicy access_;
  CorsPolicy cors_;
  TileCache cache_;
  Tiles3dService tiles3d_;
  ReportsService reports_;
  ShadowService shadows_;
  bool ready_ = false;
};

// "a=1&b=x%20y" -> {a: 1, b: "x y"}.
std::map<std::string, std::string> ParseQuery(const std::string& query);

}  // namespace pointdag::server
