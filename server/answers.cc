#include "answers.h"

#include <spdlog/spdlog.h>

#include "pointdag/json_text.h"

namespace pointdag::server {
namespace {

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

std::string HttpRequest::Header(const std::string& lower_name) const {
  const auto it = headers.find(lower_name);
  return it == headers.end() ? "" : it->second;
}

void HttpResponse::SetHeader(const std::string& name, const std::string& value) { headers.emplace_back(name, value); }

HttpResponse JsonAnswer(int status, const nlohmann::json& body, const std::string& route) {
  HttpResponse r;
  r.status = status;
  r.route = route;
  r.body = DumpJson(body, 2) + "\n";
  r.SetHeader("Content-Type", "application/json");
  r.SetHeader("Cache-Control", "no-store");
  return r;
}

HttpResponse FailAnswer(int status, const std::string& message, const std::string& route) {
  return JsonAnswer(status, {{"error", message}}, route);
}

HttpResponse StoreFailureAnswer(const Status& status, const std::string& route) {
  if (status.code() == StatusCode::kResourceLimit) {
    HttpResponse r = FailAnswer(503, "the store is busy: " + status.message(), route);
    r.SetHeader("Retry-After", "1");
    return r;
  }
  return FailAnswer(500, "the store failed: " + status.ToString(), route);
}

HttpResponse NotFoundAnswer(Store& store, const std::string& dataset, const std::string& what, const std::string& route) {
  const auto meta = store.GetDataset(dataset);
  if (!meta.ok()) return StoreFailureAnswer(meta.status(), route);
  return FailAnswer(404, *meta ? what : "no dataset " + dataset, route);
}

HttpResponse ImmutableAnswer(const HttpRequest& request, const StoredTile& body, const std::string& content_type,
                             const std::string& route) {
  HttpResponse r;
  r.route = route;
  r.SetHeader("ETag", body.etag);
  r.SetHeader("Cache-Control", "public, max-age=31536000, immutable");
  r.SetHeader("Accept-Ranges", "bytes");
  if (const std::string inm = request.Header("if-none-match"); !inm.empty() && EtagMatches(inm, body.etag)) {
    r.status = 304;
    return r;
  }
  r.SetHeader("Content-Type", content_type);
  const uint64_t size = body.bytes.size();
  const std::string if_range = request.Header("if-range");
  const bool range_applies = if_range.empty() || if_range == body.etag;
  const auto range = range_applies ? ParseRange(request.Header("range"), size) : std::nullopt;
  if (range && range->first > range->second) {
    HttpResponse e = FailAnswer(416, "the range lies outside the resource's " + std::to_string(size) + " bytes", route);
    e.SetHeader("Content-Range", "bytes */" + std::to_string(size));
    return e;
  }
  if (range) {
    r.status = 206;
    r.SetHeader("Content-Range", "bytes " + std::to_string(range->first) + "-" + std::to_string(range->second) + "/" +
                                     std::to_string(size));
    r.body.assign(body.bytes.begin() + static_cast<long>(range->first), body.bytes.begin() + static_cast<long>(range->second + 1));
  } else {
    r.body.assign(body.bytes.begin(), body.bytes.end());
  }
  return r;
}

std::optional<HttpResponse> RefuseCorruptTile(const StoredTile& tile, const std::string& dataset, const std::string& address,
                                              Metrics& metrics, const std::string& route) {
  if (TileEtag(tile.bytes) == tile.etag) return std::nullopt;
  metrics.CountCorruptTile();
  spdlog::error("tile {} of dataset {} is corrupt in the store: its bytes do not match their checksum {}", address, dataset,
                tile.etag);
  return FailAnswer(500, "tile " + address + " of dataset " + dataset +
                             " is corrupt in the store (its bytes do not match their checksum); run pointdagd --check",
                    route);
}

nlohmann::json JobJson(const JobRecord& job) {
  return {{"id", job.id},
          {"kind", job.kind},
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

std::optional<TileKey> ParseTileKey(const std::vector<std::string>& parts, size_t first) {
  if (parts.size() != first + 4) return std::nullopt;
  const auto level = ParseNumber<int>(parts[first]);
  const auto x = ParseNumber<uint32_t>(parts[first + 1]);
  const auto y = ParseNumber<uint32_t>(parts[first + 2]);
  const auto z = ParseNumber<uint32_t>(parts[first + 3]);
  if (!level || !x || !y || !z || *level < 0 || *level > 21) return std::nullopt;
  return TileKey{*level, *x, *y, *z};
}

std::string TileAddress(const TileKey& key) {
  return std::to_string(key.level) + "/" + std::to_string(key.x) + "/" + std::to_string(key.y) + "/" + std::to_string(key.z);
}

}  // namespace pointdag::server
