#include "service.h"

#include <cmath>

#include "pointdag/read/scan_reader.h"

namespace pointdag::server {
namespace {

std::vector<std::string> SplitPath(const std::string& path) {
  std::vector<std::string> parts;
  size_t start = 1;
  while (start <= path.size()) {
    const size_t end = path.find('/', start);
    parts.push_back(path.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  if (!parts.empty() && parts.back().empty()) parts.pop_back();
  return parts;
}

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string UrlDecode(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '+') {
      out += ' ';
    } else if (text[i] == '%' && i + 2 < text.size() + 0 && HexValue(text[i + 1]) >= 0 && HexValue(text[i + 2]) >= 0) {
      out += static_cast<char>(HexValue(text[i + 1]) * 16 + HexValue(text[i + 2]));
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out;
}

HttpResponse MethodNotAllowed(const HttpRequest& request, const std::string& route, const std::string& allow) {
  HttpResponse r = FailAnswer(405, request.method + " is not allowed here (" + allow + ")", route);
  r.SetHeader("Allow", allow);
  return r;
}

std::string PathOf(const std::string& target) { return target.substr(0, target.find('?')); }

std::string QueryOf(const std::string& target) {
  const size_t q = target.find('?');
  return q == std::string::npos ? "" : target.substr(q + 1);
}

}  // namespace

std::map<std::string, std::string> ParseQuery(const std::string& query) {
  std::map<std::string, std::string> out;
  size_t start = 0;
  while (start < query.size()) {
    size_t end = query.find('&', start);
    if (end == std::string::npos) end = query.size();
    const std::string pair = query.substr(start, end - start);
    const size_t eq = pair.find('=');
    if (!pair.empty()) out[UrlDecode(pair.substr(0, eq))] = eq == std::string::npos ? "" : UrlDecode(pair.substr(eq + 1));
    start = end + 1;
  }
  return out;
}

Service::Service(Store& store, JobQueue& jobs, Metrics& metrics, ServiceConfig config)
    : store_(store),
      jobs_(jobs),
      metrics_(metrics),
      config_(std::move(config)),
      access_(config_.token, config_.read_token, config_.require_token_for_reads),
      cors_(config_.cors_origins),
      cache_(config_.tile_cache_bytes),
      tiles3d_(store_, metrics_, config_.tiles3d_cache_bytes),
      reports_(config_.reports_dir),
      shadows_(store_, jobs_, metrics_) {}

void Service::AddCors(HttpResponse& response, const std::string& origin) const {
  for (auto& [name, value] : cors_.Headers(origin)) response.SetHeader(name, value);
}

HttpResponse Service::Error(int status, const std::string& message, const std::string& route) const {
  HttpResponse r = FailAnswer(status, message, route);
  AddCors(r);
  return r;
}

std::optional<HttpResponse> Service::Deny(const HttpRequest& request, Scope needed, const std::string& route) const {
  switch (access_.Check(request.Header("authorization"), needed)) {
    case AccessPolicy::Verdict::kAllowed:
      return std::nullopt;
    case AccessPolicy::Verdict::kMalformed:
      return FailAnswer(400, "send one Authorization header with one 'Bearer <token>'", route);
    case AccessPolicy::Verdict::kForbidden:
      return FailAnswer(403, "this token may only read; writes need the write token", route);
    case AccessPolicy::Verdict::kUnauthenticated:
      break;
  }
  HttpResponse r = FailAnswer(401, needed == Scope::kWrite ? "this daemon needs 'Authorization: Bearer <token>' for writes"
                                                           : "this daemon needs 'Authorization: Bearer <token>' for reads",
                              route);
  r.SetHeader("WWW-Authenticate", "Bearer");
  return r;
}

bool Service::IsUpload(const HttpRequest& request) const {
  return request.method == "POST" && PathOf(request.target) == "/v1/datasets";
}

std::optional<HttpResponse> Service::AdmitUpload(const HttpRequest& request) const {
  auto r = Admit(request);
  if (r) AddCors(*r, request.Header("origin"));
  return r;
}

HttpResponse Service::FinishUpload(const HttpRequest& request, const std::filesystem::path& file) {
  HttpResponse r = Finish(request, file);
  AddCors(r, request.Header("origin"));
  return r;
}

HttpResponse Service::Handle(const HttpRequest& request) {
  HttpResponse r = Route(request);
  AddCors(r, request.Header("origin"));
  return r;
}

std::optional<HttpResponse> Service::Admit(const HttpRequest& request) const {
  const std::string route = "/v1/datasets";
  if (auto denied = Deny(request, Scope::kWrite, route)) return denied;
  const auto query = ParseQuery(QueryOf(request.target));
  for (const auto& [key, value] : query) {
    if (key != "name" && key != "voxel" && key != "epsg" && key != "quality") {
      return FailAnswer(400, "unknown query parameter '" + key + "' (name, voxel, epsg, quality)", route);
    }
  }
  if (query.count("voxel")) {
    const auto v = ParseNumber<double>(query.at("voxel"));
    if (!v || !std::isfinite(*v) || *v <= 0) return FailAnswer(400, "voxel must be a positive number", route);
  }
  if (query.count("epsg")) {
    const auto v = ParseNumber<int>(query.at("epsg"));
    if (!v || *v <= 0) return FailAnswer(400, "epsg must be a positive integer EPSG code", route);
  }
  if (query.count("quality")) {
    const auto v = ParseNumber<double>(query.at("quality"));
    if (!v || !std::isfinite(*v) || *v < 10 || *v > 80) return FailAnswer(400, "quality must be a PSNR-Y in dB between 10 and 80", route);
  }
  const std::string length = request.Header("content-length");
  if (!length.empty()) {
    const auto n = ParseNumber<uint64_t>(length);
    if (!n) return FailAnswer(400, "Content-Length is not a number", route);
    if (*n > config_.max_upload_bytes) {
      return FailAnswer(413, "the upload is " + length + " bytes; this daemon takes at most " +
                                 std::to_string(config_.max_upload_bytes), route);
    }
  } else if (request.Header("transfer-encoding").empty()) {
    return FailAnswer(411, "an upload needs Content-Length or chunked transfer encoding", route);
  }
  if (jobs_.full()) {
    HttpResponse r = FailAnswer(503, "the job queue is full; try again later", route);
    r.SetHeader("Retry-After", "30");
    return r;
  }
  return std::nullopt;
}

HttpResponse Service::Finish(const HttpRequest& request, const std::filesystem::path& file) {
  const std::string route = "/v1/datasets";
  std::error_code ec;
  const auto remove_upload = [&] { std::filesystem::remove(file, ec); };
  if (std::filesystem::file_size(file, ec) == 0) {
    remove_upload();
    return FailAnswer(400, "the upload is empty: send a LAS, LAZ, PLY or PCD scan as the body", route);
  }
  // The reader validates every header field against the real size before a job is made.
  auto scan = OpenScan(file);
  if (!scan.ok()) {
    remove_upload();
    const int status = scan.status().code() == StatusCode::kUnsupported ? 415 : 400;
    std::string message = scan.status().ToString();  // in the upload's words, not our file's name
    for (size_t at; (at = message.find(file.string())) != std::string::npos;) message.replace(at, file.string().size(), "the upload");
    return FailAnswer(status, message, route);
  }
  const auto query = ParseQuery(QueryOf(request.target));
  JobRecord job;
  job.id = NewId();
  job.upload_path = file.string();
  job.params = {{"name", query.count("name") ? query.at("name") : std::string("scan")}};
  if (query.count("voxel")) job.params["voxel"] = *ParseNumber<double>(query.at("voxel"));
  if (query.count("epsg")) job.params["epsg"] = *ParseNumber<int>(query.at("epsg"));
  if (query.count("quality")) job.params["quality"] = *ParseNumber<double>(query.at("quality"));
  if (const Status s = store_.CreateJob(job); !s.ok()) {
    remove_upload();
    return StoreFailureAnswer(s, route);
  }
  if (!jobs_.Submit(job.id)) {
    (void)store_.SetJobState(job.id, "failed", "the job queue was full");
    remove_upload();
    HttpResponse r = FailAnswer(503, "the job queue is full; try again later", route);
    r.SetHeader("Retry-After", "30");
    return r;
  }
  const auto stored = store_.GetJob(job.id);  // with its times; the job as sent when the read fails
  HttpResponse r = JsonAnswer(202, JobJson(stored.ok() && *stored ? **stored : job), route);
  r.SetHeader("Location", "/v1/jobs/" + job.id);
  return r;
}

HttpResponse Service::GetJob(const std::string& id) {
  const std::string route = "/v1/jobs/{id}";
  auto job = store_.GetJob(id);
  if (!job.ok()) return StoreFailureAnswer(job.status(), route);
  if (!*job) return FailAnswer(404, "no job " + id, route);
  // An end the store could not record yet is the truth about the job.
  if (const auto pending = jobs_.Pending(id)) {
    (*job)->state = pending->state;
    (*job)->error = pending->error;
  }
  return JsonAnswer(200, JobJson(**job), route);
}

HttpResponse Service::Route(const HttpRequest& request) {
  const std::string path = PathOf(request.target);
  const std::vector<std::string> parts = SplitPath(path);
  if (request.method == "OPTIONS") {  // CORS preflight
    HttpResponse r;
    r.status = 204;
    r.route = "preflight";
    r.SetHeader("Access-Control-Allow-Methods", "GET, HEAD, POST, DELETE, OPTIONS");
    r.SetHeader("Access-Control-Allow-Headers", "Range, Authorization, If-None-Match, Content-Type");
    r.SetHeader("Access-Control-Max-Age", "86400");
    return r;
  }
  const bool get = request.method == "GET" || request.method == "HEAD";
  const auto method_not_allowed = [&](const std::string& route, const std::string& allow) {
    return MethodNotAllowed(request, route, allow);
  };
  if (path == "/livez") return get ? JsonAnswer(200, {{"status", "alive"}}, path) : method_not_allowed(path, "GET");
  if (path == "/readyz") {
    if (!get) return method_not_allowed(path, "GET");
    return ready_ ? JsonAnswer(200, {{"status", "ready"}}, path) : JsonAnswer(503, {{"status", "starting"}}, path);
  }
  if (path == "/metrics") {
    if (!get) return method_not_allowed(path, "GET");
    if (auto denied = Deny(request, Scope::kRead, path)) return *denied;
    const auto jobs = store_.JobCountsByState();
    if (!jobs.ok()) return StoreFailureAnswer(jobs.status(), path);
    HttpResponse r;
    r.route = path;
    r.body = metrics_.Render(*jobs);
    r.SetHeader("Content-Type", "text/plain; version=0.0.4");
    return r;
  }
  if (path == "/reports/latest.html" || (parts.size() >= 2 && parts[0] == "v1" && parts[1] == "reports")) {
    const std::string route = path == "/reports/latest.html" ? path : parts.size() == 2 ? "/v1/reports" : "/v1/reports/{id}";
    if (!get) return method_not_allowed(route, "GET");
    if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
    return path == "/reports/latest.html" ? reports_.Latest() : reports_.Get({parts.begin() + 2, parts.end()});
  }
  if (parts.size() == 3 && parts[0] == "v1" && parts[1] == "jobs") {
    const std::string route = "/v1/jobs/{id}";
    if (!get) return method_not_allowed(route, "GET");
    if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
    return GetJob(parts[2]);
  }
  if (parts.size() >= 2 && parts[0] == "v1" && parts[1] == "datasets") {
    if (parts.size() == 2) {
      const std::string route = "/v1/datasets";
      if (!get) return method_not_allowed(route, "GET, POST");
      if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
      const auto list = store_.ListDatasets();
      return list.ok() ? JsonAnswer(200, {{"datasets", *list}}, route) : StoreFailureAnswer(list.status(), route);
    }
    const std::string& id = parts[2];
    if (parts.size() == 3) {
      const std::string route = "/v1/datasets/{id}";
      if (request.method == "DELETE") {
        if (auto denied = Deny(request, Scope::kWrite, route)) return *denied;
        const auto deleted = store_.DeleteDataset(id);
        if (!deleted.ok()) return StoreFailureAnswer(deleted.status(), route);
        if (!*deleted) return FailAnswer(404, "no dataset " + id, route);
        cache_.EraseDataset(id);
        tiles3d_.EraseDataset(id);
        shadows_.ForgetDataset(id);
        HttpResponse r;
        r.status = 204;
        r.route = route;
        return r;
      }
      if (!get) return method_not_allowed(route, "GET, DELETE");
      if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
      const auto meta = store_.GetDataset(id);
      if (!meta.ok()) return StoreFailureAnswer(meta.status(), route);
      return *meta ? JsonAnswer(200, **meta, route) : FailAnswer(404, "no dataset " + id, route);
    }
    if (parts[3] == "tiles" || parts[3] == "hierarchy") {
      const std::string route = "/v1/datasets/{id}/" + parts[3];
      if (!get) return method_not_allowed(route, "GET");
      if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
      const auto key = ParseTileKey(parts, 4);
      if (!key) return FailAnswer(400, "a tile is addressed as " + parts[3] + "/{level}/{x}/{y}/{z} with level 0..21", route);
      return parts[3] == "tiles" ? GetTile(request, id, *key) : GetHierarchy(request, id, *key);
    }
    if (parts[3] == "3dtiles") {
      const std::string route = "/v1/datasets/{id}/3dtiles";
      if (!get) return method_not_allowed(route, "GET");
      if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
      return tiles3d_.Get(request, id, {parts.begin() + 4, parts.end()});
    }
    if (parts[3] == "shadows") return RouteShadows(request, id, parts);
  }
  if (get) {
    if (config_.web) {
      if (auto page = config_.web->Serve(request, path)) return *page;
    }
    if (path == "/") {
      return FailAnswer(404, "the web viewer is not installed in this daemon: build it (scripts/build runs web/build.mjs) "
                             "and point web_dir (--web-dir) at the output, build/web", "/");
    }
  }
  return FailAnswer(404, "no such resource: " + path, "other");
}

HttpResponse Service::RouteShadows(const HttpRequest& request, const std::string& id, const std::vector<std::string>& parts) {
  const bool get = request.method == "GET" || request.method == "HEAD";
  if (parts.size() == 5 && (parts[4] == "dag" || parts[4] == "query")) {
    const std::string route = parts[4] == "dag" ? ShadowService::kDagRoute : ShadowService::kQueryRoute;
    if (!get) return MethodNotAllowed(request, route, "GET");
    if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
    if (parts[4] == "dag") return shadows_.GetDag(request, id);
    return shadows_.Query(id, ParseQuery(QueryOf(request.target)));
  }
  if (parts.size() > 4) {
    const std::string route = ShadowService::kTilesRoute;
    if (!get) return MethodNotAllowed(request, route, "GET");
    if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
    const auto key = parts[4] == "tiles" ? ParseTileKey(parts, 5) : std::nullopt;
    if (!key) return FailAnswer(400, "a shadow layer is addressed as shadows/tiles/{level}/{x}/{y}/{z} with level 0..21", route);
    return shadows_.GetLayer(request, id, *key);
  }
  const std::string route = ShadowService::kRoute;
  if (request.method == "POST" || request.method == "DELETE") {
    if (auto denied = Deny(request, Scope::kWrite, route)) return *denied;
    return request.method == "POST" ? shadows_.Post(request, id) : shadows_.Delete(id);
  }
  if (!get) return MethodNotAllowed(request, route, "GET, POST, DELETE");
  if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
  return shadows_.Get(id);
}

HttpResponse Service::GetTile(const HttpRequest& request, const std::string& dataset, const TileKey& key) {
  const std::string route = "/v1/datasets/{id}/tiles";
  const std::string address = TileAddress(key);
  const std::string cache_key = dataset + "/" + address;
  std::shared_ptr<const StoredTile> tile = cache_.Get(cache_key);
  if (!tile) {
    const uint64_t generation = cache_.generation();  // before the read: a DELETE meanwhile keeps it out of the cache
    auto stored = store_.GetTile(dataset, key);
    if (!stored.ok()) return StoreFailureAnswer(stored.status(), route);
    if (!*stored) return NotFoundAnswer(store_, dataset, "no tile " + address + " in this dataset", route);
    if (auto corrupt = RefuseCorruptTile(**stored, dataset, address, metrics_, route)) return *corrupt;
    tile = std::make_shared<const StoredTile>(std::move(**stored));
    cache_.Put(cache_key, tile, generation);
  }
  return ImmutableAnswer(request, *tile, "application/vnd.pointdag.tile", route);
}

HttpResponse Service::GetHierarchy(const HttpRequest& request, const std::string& dataset, const TileKey& key) {
  const std::string route = "/v1/datasets/{id}/hierarchy";
  const auto query = ParseQuery(QueryOf(request.target));
  int depth = 4;
  if (query.count("depth")) {
    const auto d = ParseNumber<int>(query.at("depth"));
    if (!d || *d < 0 || *d > 8) return FailAnswer(400, "depth must be 0..8", route);
    depth = *d;
  }
  std::vector<TileKey> more;
  const auto tiles = store_.TilesBelow(dataset, key, depth, more);
  if (!tiles.ok()) return StoreFailureAnswer(tiles.status(), route);
  if (tiles->empty()) return NotFoundAnswer(store_, dataset, "no tile at this node", route);
  const auto key_json = [](const TileKey& k) { return nlohmann::json{{"level", k.level}, {"x", k.x}, {"y", k.y}, {"z", k.z}}; };
  nlohmann::json list = nlohmann::json::array(), pages = nlohmann::json::array();
  for (const HierarchyEntry& e : *tiles) {
    nlohmann::json j = key_json(e.key);
    j["voxels"] = e.voxels;
    list.push_back(std::move(j));
  }
  for (const TileKey& k : more) pages.push_back(key_json(k));
  HttpResponse r = JsonAnswer(200, {{"node", key_json(key)}, {"depth", depth}, {"tiles", list}, {"pages", pages}}, route);
  // Immutable like the tiles it lists: a dataset never changes once visible.
  r.headers.erase(std::remove_if(r.headers.begin(), r.headers.end(), [](const auto& h) { return h.first == "Cache-Control"; }),
                  r.headers.end());
  r.SetHeader("Cache-Control", "public, max-age=31536000, immutable");
  return r;
}

}  // namespace pointdag::server
