#include "service.h"

#include <charconv>
#include <cmath>

#include <spdlog/spdlog.h>

#include "pointdag/json_text.h"
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

template <typename T>
std::optional<T> ParseNumber(const std::string& text) {
  T value{};
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

std::optional<TileKey> ParseTileKey(const std::vector<std::string>& parts, size_t first) {
  if (parts.size() != first + 4) return std::nullopt;
  const auto level = ParseNumber<int>(parts[first]);
  const auto x = ParseNumber<uint32_t>(parts[first + 1]);
  const auto y = ParseNumber<uint32_t>(parts[first + 2]);
  const auto z = ParseNumber<uint32_t>(parts[first + 3]);
  if (!level || !x || !y || !z || *level < 0 || *level > 21) return std::nullopt;
  return TileKey{*level, *x, *y, *z};
}


// A single byte range of a body of `size` bytes: {first, last}, nullopt to ignore the header
// (absent, malformed, several ranges), or {1, 0} when unsatisfiable.
std::optional<std::pair<uint64_t, uint64_t>> ParseRange(const std::string& header, uint64_t size) {
  if (header.rfind("bytes=", 0) != 0 || header.find(',') != std::string::npos) return std::nullopt;
  const std::string spec = header.substr(6);
  const size_t dash = spec.find('-');
  if (dash == std::string::npos) return std::nullopt;
  const std::string a = spec.substr(0, dash), b = spec.substr(dash + 1);
  constexpr std::pair<uint64_t, uint64_t> kUnsatisfiable{1, 0};
  if (a.empty()) {  // suffix: the last b bytes
    const auto suffix = ParseNumber<uint64_t>(b);
    if (!suffix) return std::nullopt;
    if (*suffix == 0 || size == 0) return kUnsatisfiable;
    return std::pair{size - std::min(*suffix, size), size - 1};
  }
  const auto first = ParseNumber<uint64_t>(a);
  const auto last = b.empty() ? std::optional<uint64_t>(UINT64_MAX) : ParseNumber<uint64_t>(b);
  if (!first || !last || *last < *first) return std::nullopt;
  if (*first >= size) return kUnsatisfiable;
  return std::pair{*first, std::min(*last, size - 1)};
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

std::string PathOf(const std::string& target) { return target.substr(0, target.find('?')); }

std::string QueryOf(const std::string& target) {
  const size_t q = target.find('?');
  return q == std::string::npos ? "" : target.substr(q + 1);
}

}  // namespace

bool EtagMatches(const std::string& if_none_match, const std::string& etag) {
  // "*" matches any tag only as the whole field value (RFC 9110 13.1.2), never inside a tag.
  const size_t first = if_none_match.find_first_not_of(" \t"), last = if_none_match.find_last_not_of(" \t");
  if (first != std::string::npos && if_none_match.substr(first, last - first + 1) == "*") return true;
  // A list of entity tags; the weak comparison applies to If-None-Match.
  size_t pos = 0;
  while ((pos = if_none_match.find('"', pos)) != std::string::npos) {
    const size_t end = if_none_match.find('"', pos + 1);
    if (end == std::string::npos) break;
    if (if_none_match.compare(pos, end - pos + 1, etag) == 0) return true;
    pos = end + 1;
  }
  return false;
}

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

std::string HttpRequest::Header(const std::string& lower_name) const {
  const auto it = headers.find(lower_name);
  return it == headers.end() ? "" : it->second;
}

void HttpResponse::SetHeader(const std::string& name, const std::string& value) { headers.emplace_back(name, value); }

Service::Service(Store& store, JobQueue& jobs, Metrics& metrics, ServiceConfig config)
    : store_(store),
      jobs_(jobs),
      metrics_(metrics),
      config_(std::move(config)),
      access_(config_.token, config_.read_token, config_.require_token_for_reads),
      cors_(config_.cors_origins),
      cache_(config_.tile_cache_bytes) {}

void Service::AddCors(HttpResponse& response, const std::string& origin) const {
  for (auto& [name, value] : cors_.Headers(origin)) response.SetHeader(name, value);
}

HttpResponse Service::Json(int status, const nlohmann::json& body, const std::string& route) const {
  HttpResponse r;
  r.status = status;
  r.route = route;
  r.body = DumpJson(body, 2) + "\n";
  r.SetHeader("Content-Type", "application/json");
  r.SetHeader("Cache-Control", "no-store");
  return r;
}

HttpResponse Service::Fail(int status, const std::string& message, const std::string& route) const {
  return Json(status, {{"error", message}}, route);
}

HttpResponse Service::Error(int status, const std::string& message, const std::string& route) const {
  HttpResponse r = Fail(status, message, route);
  AddCors(r);
  return r;
}

HttpResponse Service::StoreFailure(const Status& status, const std::string& route) const {
  if (status.code() == StatusCode::kResourceLimit) {
    HttpResponse r = Fail(503, "the store is busy: " + status.message(), route);
    r.SetHeader("Retry-After", "1");
    return r;
  }
  return Fail(500, "the store failed: " + status.ToString(), route);
}

std::optional<HttpResponse> Service::Deny(const HttpRequest& request, Scope needed, const std::string& route) const {
  switch (access_.Check(request.Header("authorization"), needed)) {
    case AccessPolicy::Verdict::kAllowed:
      return std::nullopt;
    case AccessPolicy::Verdict::kMalformed:
      return Fail(400, "send one Authorization header with one 'Bearer <token>'", route);
    case AccessPolicy::Verdict::kForbidden:
      return Fail(403, "this token may only read; writes need the write token", route);
    case AccessPolicy::Verdict::kUnauthenticated:
      break;
  }
  HttpResponse r = Fail(401, needed == Scope::kWrite ? "this daemon needs 'Authorization: Bearer <token>' for writes"
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
      return Fail(400, "unknown query parameter '" + key + "' (name, voxel, epsg, quality)", route);
    }
  }
  if (query.count("voxel")) {
    const auto v = ParseNumber<double>(query.at("voxel"));
    if (!v || !std::isfinite(*v) || *v <= 0) return Fail(400, "voxel must be a positive number", route);
  }
  if (query.count("epsg")) {
    const auto v = ParseNumber<int>(query.at("epsg"));
    if (!v || *v <= 0) return Fail(400, "epsg must be a positive integer EPSG code", route);
  }
  if (query.count("quality")) {
    const auto v = ParseNumber<double>(query.at("quality"));
    if (!v || !std::isfinite(*v) || *v < 10 || *v > 80) return Fail(400, "quality must be a PSNR-Y in dB between 10 and 80", route);
  }
  const std::string length = request.Header("content-length");
  if (!length.empty()) {
    const auto n = ParseNumber<uint64_t>(length);
    if (!n) return Fail(400, "Content-Length is not a number", route);
    if (*n > config_.max_upload_bytes) {
      return Fail(413, "the upload is " + length + " bytes; this daemon takes at most " +
                           std::to_string(config_.max_upload_bytes), route);
    }
  } else if (request.Header("transfer-encoding").empty()) {
    return Fail(411, "an upload needs Content-Length or chunked transfer encoding", route);
  }
  if (jobs_.full()) {
    HttpResponse r = Fail(503, "the job queue is full; try again later", route);
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
    return Fail(400, "the upload is empty: send a LAS, PLY or PCD scan as the body", route);
  }
  // The reader validates every header field against the real size before a job is made.
  auto scan = OpenScan(file);
  if (!scan.ok()) {
    remove_upload();
    const int status = scan.status().code() == StatusCode::kUnsupported ? 415 : 400;
    std::string message = scan.status().ToString();  // in the upload's words, not our file's name
    for (size_t at; (at = message.find(file.string())) != std::string::npos;) message.replace(at, file.string().size(), "the upload");
    return Fail(status, message, route);
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
    return StoreFailure(s, route);
  }
  if (!jobs_.Submit(job.id)) {
    (void)store_.SetJobState(job.id, "failed", "the job queue was full");
    remove_upload();
    HttpResponse r = Fail(503, "the job queue is full; try again later", route);
    r.SetHeader("Retry-After", "30");
    return r;
  }
  const auto stored = store_.GetJob(job.id);  // with its times; the job as sent when the read fails
  HttpResponse r = Json(202, JobJson(stored.ok() && *stored ? **stored : job), route);
  r.SetHeader("Location", "/v1/jobs/" + job.id);
  return r;
}

HttpResponse Service::GetJob(const std::string& id) {
  const std::string route = "/v1/jobs/{id}";
  auto job = store_.GetJob(id);
  if (!job.ok()) return StoreFailure(job.status(), route);
  if (!*job) return Fail(404, "no job " + id, route);
  // An end the store could not record yet is the truth about the job.
  if (const auto pending = jobs_.Pending(id)) {
    (*job)->state = pending->state;
    (*job)->error = pending->error;
  }
  return Json(200, JobJson(**job), route);
}

nlohmann::json Service::JobJson(const JobRecord& job) {
  return {{"id", job.id},
          {"status", job.state},
          {"stage", job.stage},
          {"percent", job.percent},
          {"points_in", job.points_in},
          {"voxels_out", job.voxels_out},
          {"dataset_id", job.dataset_id.empty() ? nlohmann::json() : nlohmann::json(job.dataset_id)},
          {"dataset", job.dataset_id.empty() ? nlohmann::json() : nlohmann::json("/v1/datasets/" + job.dataset_id)},
          {"error", job.error.empty() ? nlohmann::json() : nlohmann::json(job.error)},
          {"params", job.params},
          {"created", job.created},
          {"updated", job.updated}};
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
    HttpResponse r = Fail(405, request.method + " is not allowed here (" + allow + ")", route);
    r.SetHeader("Allow", allow);
    return r;
  };
  if (path == "/livez") return get ? Json(200, {{"status", "alive"}}, path) : method_not_allowed(path, "GET");
  if (path == "/readyz") {
    if (!get) return method_not_allowed(path, "GET");
    return ready_ ? Json(200, {{"status", "ready"}}, path) : Json(503, {{"status", "starting"}}, path);
  }
  if (path == "/metrics") {
    if (!get) return method_not_allowed(path, "GET");
    if (auto denied = Deny(request, Scope::kRead, path)) return *denied;
    const auto jobs = store_.JobCountsByState();
    if (!jobs.ok()) return StoreFailure(jobs.status(), path);
    HttpResponse r;
    r.route = path;
    r.body = metrics_.Render(*jobs);
    r.SetHeader("Content-Type", "text/plain; version=0.0.4");
    return r;
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
      return list.ok() ? Json(200, {{"datasets", *list}}, route) : StoreFailure(list.status(), route);
    }
    const std::string& id = parts[2];
    if (parts.size() == 3) {
      const std::string route = "/v1/datasets/{id}";
      if (request.method == "DELETE") {
        if (auto denied = Deny(request, Scope::kWrite, route)) return *denied;
        const auto deleted = store_.DeleteDataset(id);
        if (!deleted.ok()) return StoreFailure(deleted.status(), route);
        if (!*deleted) return Fail(404, "no dataset " + id, route);
        cache_.EraseDataset(id);
        HttpResponse r;
        r.status = 204;
        r.route = route;
        return r;
      }
      if (!get) return method_not_allowed(route, "GET, DELETE");
      if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
      const auto meta = store_.GetDataset(id);
      if (!meta.ok()) return StoreFailure(meta.status(), route);
      return *meta ? Json(200, **meta, route) : Fail(404, "no dataset " + id, route);
    }
    if (parts[3] == "tiles" || parts[3] == "hierarchy") {
      const std::string route = "/v1/datasets/{id}/" + parts[3];
      if (!get) return method_not_allowed(route, "GET");
      if (auto denied = Deny(request, Scope::kRead, route)) return *denied;
      const auto key = ParseTileKey(parts, 4);
      if (!key) return Fail(400, "a tile is addressed as " + parts[3] + "/{level}/{x}/{y}/{z} with level 0..21", route);
      return parts[3] == "tiles" ? GetTile(request, id, *key) : GetHierarchy(request, id, *key);
    }
  }
  if (get) {
    if (config_.web) {
      if (auto page = config_.web->Serve(request, path)) return *page;
    }
    if (path == "/") {
      return Fail(404, "the web viewer is not installed in this daemon: build it (scripts/build runs web/build.mjs) and "
                       "point web_dir (--web-dir) at the output, build/web", "/");
    }
  }
  return Fail(404, "no such resource: " + path, "other");
}

HttpResponse Service::NotFound(const std::string& dataset, const std::string& what, const std::string& route) {
  const auto meta = store_.GetDataset(dataset);
  if (!meta.ok()) return StoreFailure(meta.status(), route);
  return Fail(404, *meta ? what : "no dataset " + dataset, route);
}

HttpResponse Service::GetTile(const HttpRequest& request, const std::string& dataset, const TileKey& key) {
  const std::string route = "/v1/datasets/{id}/tiles";
  const std::string address = std::to_string(key.level) + "/" + std::to_string(key.x) + "/" + std::to_string(key.y) + "/" +
                              std::to_string(key.z);
  const std::string cache_key = dataset + "/" + address;
  std::shared_ptr<const StoredTile> tile = cache_.Get(cache_key);
  if (!tile) {
    const uint64_t generation = cache_.generation();  // before the read: a DELETE meanwhile keeps it out of the cache
    auto stored = store_.GetTile(dataset, key);
    if (!stored.ok()) return StoreFailure(stored.status(), route);
    if (!*stored) return NotFound(dataset, "no tile " + address + " in this dataset", route);
    // Never serve bytes that are not what was committed: the ETag is their checksum.
    if (TileEtag((*stored)->bytes) != (*stored)->etag) {
      metrics_.CountCorruptTile();
      spdlog::error("tile {} of dataset {} is corrupt in the store: its bytes do not match their checksum {}", address,
                    dataset, (*stored)->etag);
      return Fail(500, "tile " + address + " of dataset " + dataset +
                           " is corrupt in the store (its bytes do not match their checksum); run pointdagd --check", route);
    }
    tile = std::make_shared<const StoredTile>(std::move(**stored));
    cache_.Put(cache_key, tile, generation);
  }
  HttpResponse r;
  r.route = route;
  r.SetHeader("ETag", tile->etag);
  r.SetHeader("Cache-Control", "public, max-age=31536000, immutable");
  r.SetHeader("Accept-Ranges", "bytes");
  if (const std::string inm = request.Header("if-none-match"); !inm.empty() && EtagMatches(inm, tile->etag)) {
    r.status = 304;
    return r;
  }
  r.SetHeader("Content-Type", "application/vnd.pointdag.tile");
  const uint64_t size = tile->bytes.size();
  const std::string if_range = request.Header("if-range");
  const bool range_applies = if_range.empty() || if_range == tile->etag;
  const auto range = range_applies ? ParseRange(request.Header("range"), size) : std::nullopt;
  if (range && range->first > range->second) {
    HttpResponse e = Fail(416, "the range lies outside the tile's " + std::to_string(size) + " bytes", route);
    e.SetHeader("Content-Range", "bytes */" + std::to_string(size));
    return e;
  }
  if (range) {
    r.status = 206;
    r.SetHeader("Content-Range", "bytes " + std::to_string(range->first) + "-" + std::to_string(range->second) + "/" +
                                     std::to_string(size));
    r.body.assign(tile->bytes.begin() + static_cast<long>(range->first), tile->bytes.begin() + static_cast<long>(range->second + 1));
  } else {
    r.body.assign(tile->bytes.begin(), tile->bytes.end());
  }
  return r;
}

HttpResponse Service::GetHierarchy(const HttpRequest& request, const std::string& dataset, const TileKey& key) {
  const std::string route = "/v1/datasets/{id}/hierarchy";
  const auto query = ParseQuery(QueryOf(request.target));
  int depth = 4;
  if (query.count("depth")) {
    const auto d = ParseNumber<int>(query.at("depth"));
    if (!d || *d < 0 || *d > 8) return Fail(400, "depth must be 0..8", route);
    depth = *d;
  }
  std::vector<TileKey> more;
  const auto tiles = store_.TilesBelow(dataset, key, depth, more);
  if (!tiles.ok()) return StoreFailure(tiles.status(), route);
  if (tiles->empty()) return NotFound(dataset, "no tile at this node", route);
  const auto key_json = [](const TileKey& k) { return nlohmann::json{{"level", k.level}, {"x", k.x}, {"y", k.y}, {"z", k.z}}; };
  nlohmann::json list = nlohmann::json::array(), pages = nlohmann::json::array();
  for (const HierarchyEntry& e : *tiles) {
    nlohmann::json j = key_json(e.key);
    j["voxels"] = e.voxels;
    list.push_back(std::move(j));
  }
  for (const TileKey& k : more) pages.push_back(key_json(k));
  HttpResponse r = Json(200, {{"node", key_json(key)}, {"depth", depth}, {"tiles", list}, {"pages", pages}}, route);
  // Immutable like the tiles it lists: a dataset never changes once visible.
  r.headers.erase(std::remove_if(r.headers.begin(), r.headers.end(), [](const auto& h) { return h.first == "Cache-Control"; }),
                  r.headers.end());
  r.SetHeader("Cache-Control", "public, max-age=31536000, immutable");
  return r;
}

}  // namespace pointdag::server
