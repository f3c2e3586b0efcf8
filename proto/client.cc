#include "client.h"

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <nlohmann/json.hpp>

#include <charconv>
#include <deque>
#include <set>

#include "pointdag/container/json_fields.h"
#include "pointdag/container/pdag_file.h"
#include "pointdag/json_text.h"
#include "pointdag/pipeline.h"
#include "pointdag/voxelize/morton.h"

namespace pointdag::client {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;

std::string Response::Header(const std::string& lower_name) const {
  const auto it = headers.find(lower_name);
  return it == headers.end() ? "" : it->second;
}

StatusOr<Url> ParseUrl(const std::string& url) {
  constexpr std::string_view scheme = "http://";
  if (url.rfind(scheme, 0) != 0) return InvalidArgument("only http:// URLs are supported: '" + url + "'");
  const std::string rest = url.substr(scheme.size());
  const size_t slash = rest.find('/');
  const std::string authority = rest.substr(0, slash);
  Url out;
  out.target = slash == std::string::npos ? "/" : rest.substr(slash);
  const size_t colon = authority.rfind(':');
  out.host = authority.substr(0, colon);
  if (colon != std::string::npos) {
    unsigned port = 0;
    const char* end = authority.data() + authority.size();
    const auto [ptr, ec] = std::from_chars(authority.data() + colon + 1, end, port);
    if (ec != std::errc() || ptr != end || port == 0 || port > 65535) return InvalidArgument("bad port in '" + url + "'");
    out.port = static_cast<uint16_t>(port);
  }
  if (out.host.empty()) return InvalidArgument("no host in '" + url + "'");
  return out;
}

struct Connection::Impl {
  asio::io_context io;
  beast::tcp_stream stream{io};
  beast::flat_buffer buffer;
  std::string host;
  uint64_t max_body_bytes = kDefaultMaxBodyBytes;

  template <typename Body>
  StatusOr<Response> Exchange(http::request<Body>& request) {
    request.set(http::field::host, host);
    request.set(http::field::user_agent, "pointdag-client/0.1");
    beast::error_code ec;
    stream.expires_after(std::chrono::minutes(10));
    http::write(stream, request, ec);
    if (ec) return IoError("sending the request failed: " + ec.message());
    http::response_parser<http::string_body> parser;
    parser.body_limit(max_body_bytes);
    if (request.method() == http::verb::head) parser.skip(true);
    // The header first: a declared length above the limit is refused before the body reader
    // would reserve it.
    http::read_header(stream, buffer, parser, ec);
    const auto declared = parser.content_length();
    if (ec == http::error::body_limit || (!ec && declared && *declared > max_body_bytes)) {
      return ResourceLimit("the response body is larger than the " + std::to_string(max_body_bytes) + " bytes allowed");
    }
    if (!ec) http::read(stream, buffer, parser, ec);
    if (ec == http::error::body_limit) {
      return ResourceLimit("the response body is larger than the " + std::to_string(max_body_bytes) + " bytes allowed");
    }
    if (ec) return IoError("reading the response failed: " + ec.message());
    Response out;
    out.status = static_cast<int>(parser.get().result_int());
    for (const auto& field : parser.get()) {
      std::string name(field.name_string());
      for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      out.headers[name] = std::string(field.value());
    }
    out.body = std::move(parser.get().body());
    return out;
  }
};

Connection::Connection(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Connection::~Connection() {
  beast::error_code ignored;
  impl_->stream.socket().shutdown(tcp::socket::shutdown_both, ignored);
}

StatusOr<std::unique_ptr<Connection>> Connection::Open(const std::string& host, uint16_t port, uint64_t max_body_bytes) {
  auto impl = std::make_unique<Impl>();
  impl->max_body_bytes = max_body_bytes;
  impl->host = host + ":" + std::to_string(port);
  beast::error_code ec;
  tcp::resolver resolver(impl->io);
  const auto endpoints = resolver.resolve(host, std::to_string(port), ec);
  if (ec) return IoError("cannot resolve " + host + ": " + ec.message());
  impl->stream.connect(endpoints, ec);
  if (ec) return IoError("cannot connect to " + impl->host + ": " + ec.message());
  // An upload's header and body go out in separate writes: with Nagle's algorithm the body's last
  // segment waits for the daemon's delayed ACK (40 ms for every small upload; curl sets it too).
  impl->stream.socket().set_option(tcp::no_delay(true), ec);
  return std::unique_ptr<Connection>(new Connection(std::move(impl)));
}

StatusOr<Response> Connection::Request(const std::string& method, const std::string& target,
                                       const std::map<std::string, std::string>& headers, const std::string& body) {
  http::request<http::string_body> request;
  request.method_string(method);
  request.target(target);
  request.version(11);
  for (const auto& [name, value] : headers) request.set(name, value);
  request.body() = body;
  // A caller's own Content-Length stands (tests send lying ones on purpose).
  if (!headers.count("Content-Length") && (!body.empty() || method == "POST" || method == "PUT")) request.prepare_payload();
  return impl_->Exchange(request);
}

StatusOr<Response> Connection::Upload(const std::string& target, const std::filesystem::path& file,
                                      const std::map<std::string, std::string>& headers) {
  http::request<http::file_body> request;
  request.method(http::verb::post);
  request.target(target);
  request.version(11);
  for (const auto& [name, value] : headers) request.set(name, value);
  beast::error_code ec;
  request.body().open(file.c_str(), beast::file_mode::scan, ec);
  if (ec) return IoError("cannot open " + file.string() + ": " + ec.message());
  request.prepare_payload();
  return impl_->Exchange(request);
}

namespace {

StatusOr<nlohmann::json> ParseServerJson(std::string_view body, const std::string& what) {
  auto json = ParseJson(body);
  if (!json.ok()) return Malformed(what + " is not JSON: " + json.status().message());
  if (!json->is_object()) return Malformed(what + " is not a JSON object");
  return json;
}

StatusOr<TileAddress> ParseAddress(const nlohmann::json& entry, int max_level, const std::string& what) {
  const JsonFields fields(entry, what, StatusCode::kMalformed);
  TileAddress out;
  ASSIGN_OR_RETURN(const int64_t level, fields.Int("level", 0, max_level));
  out.level = static_cast<int>(level);
  const int64_t side = int64_t{1} << level;
  uint32_t* coords[3] = {&out.x, &out.y, &out.z};
  const char* names[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    ASSIGN_OR_RETURN(const int64_t v, fields.Int(names[i], 0, side - 1));
    *coords[i] = static_cast<uint32_t>(v);
  }
  return out;
}

}  // namespace

StatusOr<DatasetShape> ParseDatasetShape(std::string_view body) {
  ASSIGN_OR_RETURN(const nlohmann::json json, ParseServerJson(body, "the dataset description"));
  const JsonFields fields(json, "the dataset description", StatusCode::kMalformed);
  DatasetShape out;
  ASSIGN_OR_RETURN(static_cast<TileGridShape&>(out), ReadTileGridShape(fields));
  ASSIGN_OR_RETURN(out.points, fields.UintOr("source/points", std::numeric_limits<uint64_t>::max(), 0));
  out.has_shadows = json.contains("shadows") && json["shadows"].is_object();
  return out;
}

StatusOr<HierarchyPage> ParseHierarchyPage(std::string_view body, int max_level) {
  ASSIGN_OR_RETURN(const nlohmann::json json, ParseServerJson(body, "the hierarchy page"));
  const JsonFields fields(json, "the hierarchy page", StatusCode::kMalformed);
  HierarchyPage out;
  ASSIGN_OR_RETURN(const nlohmann::json* tiles, fields.Array("tiles"));
  for (const nlohmann::json& t : *tiles) {
    ASSIGN_OR_RETURN(TileAddress address, ParseAddress(t, max_level, "a hierarchy page's tile"));
    out.tiles.push_back(address);
  }
  // The deepest pages have no further pages: the member may be absent there.
  if (fields.Has("pages")) {
    ASSIGN_OR_RETURN(const nlohmann::json* pages, fields.Array("pages"));
    for (const nlohmann::json& p : *pages) {
      ASSIGN_OR_RETURN(TileAddress address, ParseAddress(p, max_level, "a hierarchy page's page"));
      out.pages.push_back(address);
    }
  }
  return out;
}

StatusOr<Response> GetOk(Connection& connection, const std::string& target) {
  ASSIGN_OR_RETURN(Response r, connection.Request("GET", target));
  if (r.status != 200) return IoError("GET " + target + " answered " + std::to_string(r.status) + ": " + r.body.substr(0, 200));
  return r;
}

StatusOr<std::vector<TileAddress>> ListTiles(Connection& connection, const std::string& dataset_target, int max_level,
                                             const FetchLimits& limits) {
  // Walk the hierarchy pages down to max_level; a server that repeats a page (a cycle) or never
  // stops is refused by the visited set and the limits.
  std::set<TileAddress> keys, visited;
  std::deque<TileAddress> pages = {TileAddress{}};
  while (!pages.empty()) {
    const TileAddress page = pages.front();
    pages.pop_front();
    if (!visited.insert(page).second) return Malformed("the server lists hierarchy page " + std::to_string(page.level) + "/" +
                                                       std::to_string(page.x) + "/" + std::to_string(page.y) + "/" +
                                                       std::to_string(page.z) + " twice");
    const int depth = std::min(4, max_level - page.level);
    ASSIGN_OR_RETURN(const Response r, GetOk(connection, dataset_target + "/hierarchy/" + std::to_string(page.level) + "/" +
                                                             std::to_string(page.x) + "/" + std::to_string(page.y) + "/" +
                                                             std::to_string(page.z) + "?depth=" + std::to_string(depth)));
    ASSIGN_OR_RETURN(const HierarchyPage parsed, ParseHierarchyPage(r.body, max_level));
    keys.insert(parsed.tiles.begin(), parsed.tiles.end());
    if (keys.size() > limits.max_tiles) return ResourceLimit("the dataset has more than " + std::to_string(limits.max_tiles) + " tiles");
    if (page.level + depth < max_level) {
      for (const TileAddress& p : parsed.pages) {
        if (p.level <= page.level) return Malformed("a hierarchy page lists a page that is not below it");
        pages.push_back(p);
        if (pages.size() + visited.size() > limits.max_pages) {
          return ResourceLimit("the dataset has more than " + std::to_string(limits.max_pages) + " hierarchy pages");
        }
      }
    }
  }
  return std::vector<TileAddress>(keys.begin(), keys.end());
}

StatusOr<ShadowLayer> FetchShadowLayer(Connection& connection, const std::string& dataset_target, const TileAddress& tile,
                                       uint64_t tile_voxels) {
  const std::string target = dataset_target + "/shadows/tiles/" + std::to_string(tile.level) + "/" + std::to_string(tile.x) +
                             "/" + std::to_string(tile.y) + "/" + std::to_string(tile.z);
  ASSIGN_OR_RETURN(const Response r, GetOk(connection, target));
  auto layer = DecodeShadowLayer({reinterpret_cast<const uint8_t*>(r.body.data()), r.body.size()}, tile_voxels);
  if (!layer.ok()) return Status(layer.status().code(), target + ": " + layer.status().message());
  return layer;
}

StatusOr<ShadowDag> FetchShadowDag(Connection& connection, const std::string& dataset_target) {
  const std::string target = dataset_target + "/shadows/dag";
  ASSIGN_OR_RETURN(const Response r, GetOk(connection, target));
  auto dag = ShadowDag::Deserialize({reinterpret_cast<const uint8_t*>(r.body.data()), r.body.size()});
  if (!dag.ok()) return Status(dag.status().code(), target + ": " + dag.status().message());
  return dag;
}

StatusOr<FetchedLevel> FetchDataset(const std::string& dataset_url, std::optional<int> level,
                                    const std::function<void(size_t, size_t)>& progress, const FetchLimits& limits,
                                    bool shadows) {
  ASSIGN_OR_RETURN(const Url url, ParseUrl(dataset_url));
  ASSIGN_OR_RETURN(std::unique_ptr<Connection> connection, Connection::Open(url.host, url.port, limits.max_body_bytes));
  const auto get = [&](const std::string& target) { return GetOk(*connection, target); };
  ASSIGN_OR_RETURN(const Response described, get(url.target));
  ASSIGN_OR_RETURN(const DatasetShape shape, ParseDatasetShape(described.body));
  if (shadows && !shape.has_shadows) {
    return InvalidArgument("the dataset has no shadows: POST " + url.target + "/shadows computes them (PROTOCOL.md §3.2)");
  }
  FetchedLevel out;
  out.level = level.value_or(shape.levels - 1);
  if (out.level < 0 || out.level >= shape.levels) {
    return InvalidArgument("the dataset has levels 0.." + std::to_string(shape.levels - 1) + ", not " + std::to_string(out.level));
  }
  ASSIGN_OR_RETURN(const std::vector<TileAddress> listed, ListTiles(*connection, url.target, out.level, limits));
  std::vector<TileAddress> ordered;
  std::copy_if(listed.begin(), listed.end(), std::back_inserter(ordered), [&](const TileAddress& t) { return t.level == out.level; });
  out.grid.depth = shape.tile_depth + out.level;
  out.grid.origin = shape.origin;
  out.grid.voxel_size = std::ldexp(shape.voxel_size, shape.levels - 1 - out.level);
  out.grid.points_in = shape.points;
  std::sort(ordered.begin(), ordered.end(), [](const TileAddress& a, const TileAddress& b) {
    return MortonEncode(a.x, a.y, a.z) < MortonEncode(b.x, b.y, b.z);
  });
  // A tile is a 2^tile_depth cube: that bounds each decode, whatever its metadata says.
  DecodeLimits tile_limits;
  tile_limits.max_voxels = std::min(tile_limits.max_voxels, uint64_t{1} << (3 * shape.tile_depth));
  for (const TileAddress& key : ordered) {
    const std::string target = url.target + "/tiles/" + std::to_string(out.level) + "/" + std::to_string(key.x) + "/" +
                               std::to_string(key.y) + "/" + std::to_string(key.z);
    ASSIGN_OR_RETURN(const Response r, get(target));
    const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(r.body.data()), r.body.size());
    const auto decoded = [&]() -> StatusOr<DecodedPdag> {
      ASSIGN_OR_RETURN(const PdagFile file, ParsePdag(bytes));
      return DecodePdag(file, tile_limits);
    }();
    if (!decoded.ok()) return Status(decoded.status().code(), "tile " + target + ": " + decoded.status().message());
    const DecodedPdag& tile = *decoded;
    if (tile.grid.depth != shape.tile_depth) return Corrupt("tile " + target + " is not " + std::to_string(shape.tile_depth) + " levels deep");
    if (out.tiles > 0 && tile.grid.has_color() != out.grid.has_color()) {
      return Corrupt("tile " + target + (tile.grid.has_color() ? " has colors and the tiles before it none" : " has no colors and the tiles before it have"));
    }
    if (out.grid.morton.size() + tile.grid.morton.size() > limits.max_voxels) {
      return ResourceLimit("the level holds more than " + std::to_string(limits.max_voxels) + " voxels");
    }
    const uint64_t tile_code = MortonEncode(key.x, key.y, key.z) << (3 * shape.tile_depth);
    for (uint64_t local : tile.grid.morton) out.grid.morton.push_back(tile_code | local);
    out.grid.colors.insert(out.grid.colors.end(), tile.grid.colors.begin(), tile.grid.colors.end());
    if (shadows) {
      ASSIGN_OR_RETURN(const ShadowLayer layer, FetchShadowLayer(*connection, url.target, key, tile.grid.morton.size()));
      out.light.insert(out.light.end(), layer.light.begin(), layer.light.end());
    }
    out.tile_bytes += r.body.size();
    ++out.tiles;
    if (progress) progress(out.tiles, ordered.size());
  }
  return out;
}

}  // namespace pointdag::client
