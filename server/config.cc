#include "config.h"

#include <toml++/toml.h>

#include <charconv>
#include <set>

namespace pointdag::server {

Status ParseListen(const std::string& listen, DaemonConfig& config) {
  const size_t colon = listen.rfind(':');
  if (colon == std::string::npos || colon == 0) return InvalidArgument("listen must be HOST:PORT, got '" + listen + "'");
  unsigned port = 0;
  const char* end = listen.data() + listen.size();
  const auto [ptr, ec] = std::from_chars(listen.data() + colon + 1, end, port);
  if (ec != std::errc() || ptr != end || port > 65535) return InvalidArgument("bad port in '" + listen + "'");
  config.host = listen.substr(0, colon);
  config.port = static_cast<uint16_t>(port);
  return Status::Ok();
}

Status LoadConfigFile(const std::filesystem::path& file, DaemonConfig& config) {
  toml::table table;
  try {
    table = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    return InvalidArgument(file.string() + ": " + std::string(e.description()));
  }
  static const std::set<std::string> known = {"listen", "data_dir", "token", "workers", "http_threads", "queue_size",
                                              "max_upload_bytes", "tile_cache_mb", "cors_origin", "log_level"};
  for (const auto& [key, value] : table) {
    if (!known.count(std::string(key.str()))) return InvalidArgument(file.string() + ": unknown key '" + std::string(key.str()) + "'");
  }
  if (auto v = table["listen"].value<std::string>()) RETURN_IF_ERROR(ParseListen(*v, config));
  if (auto v = table["data_dir"].value<std::string>()) config.data_dir = *v;
  if (auto v = table["token"].value<std::string>()) config.token = *v;
  if (auto v = table["workers"].value<int64_t>()) config.workers = static_cast<int>(*v);
  if (auto v = table["http_threads"].value<int64_t>()) config.http_threads = static_cast<int>(*v);
  if (auto v = table["queue_size"].value<int64_t>()) config.queue_size = static_cast<size_t>(*v);
  if (auto v = table["max_upload_bytes"].value<int64_t>()) config.max_upload_bytes = static_cast<uint64_t>(*v);
  if (auto v = table["tile_cache_mb"].value<int64_t>()) config.tile_cache_mb = static_cast<size_t>(*v);
  if (auto v = table["cors_origin"].value<std::string>()) config.cors_origin = *v;
  if (auto v = table["log_level"].value<std::string>()) config.log_level = *v;
  if (config.workers < 1 || config.http_threads < 1 || config.queue_size < 1) {
    return InvalidArgument(file.string() + ": workers, http_threads and queue_size must be at least 1");
  }
  return Status::Ok();
}

}  // namespace pointdag::server
