#include "client.h"

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <nlohmann/json.hpp>

#include <charconv>
#include <deque>

#include "pointdag/container/pdag_file.h"
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

  template <typename Body>
  StatusOr<Response> Exchange(http::request<Body>& request) {
    request.set(http::field::host, host);
    request.set(http::field::user_agent, "pointdag-client/0.1");
    beast::error_code ec;
    stream.expires_after(std::chrono::minutes(10));
    http::write(stream, request, ec);
    if (ec) return IoError("sending the request failed: " + ec.message());
    http::response_parser<http::string_body> parser;
    parser.body_limit(std::numeric_limits<std::uint64_t>::max());
    if (request.method() == http::verb::head) parser.skip(true);
    http::read(stream, buffer, parser, ec);
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

StatusOr<std::unique_ptr<Connection>> Connection::Open(const std::string& host, uint16_t port) {
  auto impl = std::make_unique<Impl>();
  impl->host = host + ":" + std::to_string(port);
  beast::error_code ec;
  tcp::resolver resolver(impl->io);
  const auto endpoints = resolver.resolve(host, std::to_string(port), ec);
  if (ec) return IoError("cannot resolve " + host + ": " + ec.message());
  impl->stream.connect(endpoints, ec);
  if (ec) return IoError("cannot connect to " + impl->host + ": " + ec.message());
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

StatusOr<FetchedLevel> FetchDataset(const std::string& dataset_url, std::optional<int> level,
                                    const std::function<void(size_t, size_t)>& progress) {
  ASSIGN_OR_RETURN(const Url url, ParseUrl(dataset_url));
  ASSIGN_OR_RETURN(std::unique_ptr<Connection> connection, Connection::Open(url.host, url.port));
  const auto get_json = [&](const std::string& target) -> StatusOr<nlohmann::json> {
    ASSIGN_OR_RETURN(const Response r, connection->Request("GET", target));
    if (r.status != 200) return IoError("GET " + target + " answered " + std::to_string(r.status) + ": " + r.body);
    auto json = nlohmann::json::parse(r.body, nullptr, false);
    if (json.is_discarded()) return Corrupt("GET " + target + " did not answer JSON");
    return json;
  };
  ASSIGN_OR_RETURN(const nlohmann::json meta, get_json(url.target));
  const int levels = meta.at("levels").get<int>();
  const int tile_depth = meta.at("tile_depth").get<int>();
  FetchedLevel out;
  out.level = level.value_or(levels - 1);
  if (out.level < 0 || out.level >= levels) {
    return InvalidArgument("the dataset has levels 0.." + std::to_string(levels - 1) + ", not " + std::to_string(out.level));
  }
  // Walk the hierarchy pages down to the wanted level.
  std::vector<std::array<uint32_t, 3>> keys;
  std::deque<std::array<uint64_t, 4>> pages = {{0, 0, 0, 0}};
  while (!pages.empty()) {
    const auto [l, x, y, z] = pages.front();
    pages.pop_front();
    const int depth = std::min(4, out.level - static_cast<int>(l));
    ASSIGN_OR_RETURN(const nlohmann::json page, get_json(url.target + "/hierarchy/" + std::to_string(l) + "/" + std::to_string(x) + "/" +
                                                         std::to_string(y) + "/" + std::to_string(z) + "?depth=" + std::to_string(depth)));
    for (const auto& t : page.at("tiles")) {
      if (t.at("level").get<int>() == out.level) keys.push_back({t["x"].get<uint32_t>(), t["y"].get<uint32_t>(), t["z"].get<uint32_t>()});
    }
    if (static_cast<int>(l) + depth < out.level) {
      for (const auto& p : page.at("pages")) pages.push_back({p["level"].get<uint64_t>(), p["x"].get<uint64_t>(), p["y"].get<uint64_t>(), p["z"].get<uint64_t>()});
    }
  }
  out.grid.depth = tile_depth + out.level;
  out.grid.origin = meta.at("bounds").at("min").get<std::array<double, 3>>();
  out.grid.voxel_size = std::ldexp(meta.at("voxel_size").get<double>(), levels - 1 - out.level);
  out.grid.points_in = meta.at("source").at("points").get<uint64_t>();
  std::sort(keys.begin(), keys.end(), [](const auto& a, const auto& b) {
    return MortonEncode(a[0], a[1], a[2]) < MortonEncode(b[0], b[1], b[2]);
  });
  for (const auto& [x, y, z] : keys) {
    const std::string target = url.target + "/tiles/" + std::to_string(out.level) + "/" + std::to_string(x) + "/" +
                               std::to_string(y) + "/" + std::to_string(z);
    ASSIGN_OR_RETURN(const Response r, connection->Request("GET", target));
    if (r.status != 200) return IoError("GET " + target + " answered " + std::to_string(r.status));
    const std::span<const uint8_t> bytes(reinterpret_cast<const uint8_t*>(r.body.data()), r.body.size());
    ASSIGN_OR_RETURN(const PdagFile file, ParsePdag(bytes));
    ASSIGN_OR_RETURN(const DecodedPdag tile, DecodePdag(file));
    const uint64_t tile_code = MortonEncode(x, y, z) << (3 * tile_depth);
    for (uint64_t local : tile.grid.morton) out.grid.morton.push_back(tile_code | local);
    out.grid.colors.insert(out.grid.colors.end(), tile.grid.colors.begin(), tile.grid.colors.end());
    out.tile_bytes += r.body.size();
    ++out.tiles;
    if (progress) progress(out.tiles, keys.size());
  }
  return out;
}

}  // namespace pointdag::client
