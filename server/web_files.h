// The web viewer's static files (web/, bundled by web/build.mjs at build time), served by pointdagd.
//
// Contract: Load() reads OUTDIR/index.html and every file of OUTDIR/assets/ into memory once, at
// start: the set is small (a few MB), immutable while the daemon runs, and holding it means no
// request can name a path outside it (no traversal, no races with a rebuild). Serve() answers
//   /, /datasets/{id}, /datasets/{id}/3dtiles  -> index.html, `Cache-Control: no-cache` (the app
//                                                routes in the browser; a shared link reloads);
//   /assets/{name}                              -> the file, `immutable` (names carry a content hash);
// with a strong ETag (304 on If-None-Match), the type from the extension, `nosniff`, and for the
// page a Content-Security-Policy that allows nothing from other origins. Anything else: nullopt.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "pointdag/status.h"

namespace pointdag::server {

struct HttpRequest;
struct HttpResponse;

class WebFiles {
 public:
  // An empty `dir` disables the viewer; a missing one is an error naming it.
  static StatusOr<WebFiles> Load(const std::filesystem::path& dir);
  WebFiles() = default;

  bool enabled() const { return !index_.body.empty(); }
  size_t file_count() const { return assets_.size() + (enabled() ? 1 : 0); }
  std::optional<HttpResponse> Serve(const HttpRequest& request, const std::string& path) const;

 private:
  struct File {
    std::string body, etag, type;
  };
  static File Make(std::string body, const std::string& type);
  std::optional<HttpResponse> Answer(const HttpRequest& request, const File& file, bool immutable) const;

  File index_;
  std::map<std::string, File, std::less<>> assets_;  // by file name
};

// The MIME type for a file name's extension (application/octet-stream when unknown).
std::string ContentTypeFor(const std::string& name);

}  // namespace pointdag::server
