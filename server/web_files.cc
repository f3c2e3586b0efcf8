#include "web_files.h"

#include <fstream>
#include <sstream>

#include "answers.h"

namespace pointdag::server {
namespace {

StatusOr<std::string> ReadWhole(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return IoError("cannot read " + file.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The app's own routes, which the page resolves in the browser.
bool IsAppRoute(const std::string& path) {
  if (path == "/" || path == "/index.html") return true;
  constexpr std::string_view prefix = "/datasets/";
  if (!path.starts_with(prefix)) return false;
  std::string_view rest = std::string_view(path).substr(prefix.size());
  if (rest.ends_with("/3dtiles")) rest.remove_suffix(std::string_view("/3dtiles").size());
  return !rest.empty() && rest.find_first_not_of("0123456789abcdefABCDEF") == std::string_view::npos;
}

// Scripts, styles, workers and WebAssembly from this origin only; the API on this origin only.
constexpr const char* kPagePolicy =
    "default-src 'self'; script-src 'self' 'wasm-unsafe-eval'; worker-src 'self' blob:; "
    "style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; connect-src 'self' blob: data:; "
    "object-src 'none'; base-uri 'none'; frame-ancestors 'none'";

}  // namespace

std::string ContentTypeFor(const std::string& name) {
  static const std::map<std::string, std::string, std::less<>> types = {
      {".html", "text/html; charset=utf-8"}, {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"}, {".css", "text/css; charset=utf-8"},
      {".wasm", "application/wasm"},          {".map", "application/json"},
      {".json", "application/json"},          {".svg", "image/svg+xml"},
      {".png", "image/png"},                  {".ico", "image/x-icon"},
      {".txt", "text/plain; charset=utf-8"}};
  const auto it = types.find(std::filesystem::path(name).extension().string());
  return it == types.end() ? "application/octet-stream" : it->second;
}

WebFiles::File WebFiles::Make(std::string body, const std::string& type) {
  File f;
  f.etag = TileEtag({reinterpret_cast<const uint8_t*>(body.data()), body.size()});
  f.body = std::move(body);
  f.type = type;
  return f;
}

StatusOr<WebFiles> WebFiles::Load(const std::filesystem::path& dir) {
  WebFiles files;
  if (dir.empty()) return files;
  ASSIGN_OR_RETURN(std::string index, ReadWhole(dir / "index.html"));
  if (index.empty()) return IoError((dir / "index.html").string() + " is empty");
  files.index_ = Make(std::move(index), ContentTypeFor("index.html"));
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "assets", ec)) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    ASSIGN_OR_RETURN(std::string body, ReadWhole(entry.path()));
    files.assets_.emplace(name, Make(std::move(body), ContentTypeFor(name)));
  }
  if (ec) return IoError("cannot list " + (dir / "assets").string() + ": " + ec.message());
  return files;
}

std::optional<HttpResponse> WebFiles::Answer(const HttpRequest& request, const File& file, bool immutable) const {
  HttpResponse r;
  r.route = immutable ? "/assets" : "/";
  r.SetHeader("ETag", file.etag);
  r.SetHeader("Cache-Control", immutable ? "public, max-age=31536000, immutable" : "no-cache");
  r.SetHeader("X-Content-Type-Options", "nosniff");
  if (!immutable) r.SetHeader("Content-Security-Policy", kPagePolicy);
  if (const std::string inm = request.Header("if-none-match"); !inm.empty() && EtagMatches(inm, file.etag)) {
    r.status = 304;
    return r;
  }
  r.SetHeader("Content-Type", file.type);
  r.body = file.body;
  return r;
}

std::optional<HttpResponse> WebFiles::Serve(const HttpRequest& request, const std::string& path) const {
  if (!enabled()) return std::nullopt;
  if (IsAppRoute(path)) return Answer(request, index_, false);
  constexpr std::string_view assets = "/assets/";
  if (path.starts_with(assets)) {
    const auto it = assets_.find(std::string_view(path).substr(assets.size()));
    if (it != assets_.end()) return Answer(request, it->second, true);
  }
  return std::nullopt;
}

}  // namespace pointdag::server
