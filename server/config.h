// pointdagd's configuration: the embedded defaults, then a TOML file (toml++), then flags (CLI11).
#pragma once

#include <filesystem>
#include <string>

#include "pointdag/status.h"

namespace pointdag::server {

struct DaemonConfig {
  std::string host = "127.0.0.1";
  uint16_t port = 8080;
  std::filesystem::path data_dir = "./var";
  std::string token;                      // empty: no token needed for writes
  int workers = 1;                        // ingest threads (each also uses the tile encoder's threads)
  int http_threads = 2;                   // threads serving HTTP
  size_t queue_size = 16;                 // jobs waiting beyond the running ones
  uint64_t max_upload_bytes = uint64_t{4} << 30;
  size_t tile_cache_mb = 256;
  std::string cors_origin = "*";
  std::string log_level = "info";
  std::filesystem::path port_file;        // where to write the bound port (for --listen HOST:0)
};

// "HOST:PORT" -> host and port.
Status ParseListen(const std::string& listen, DaemonConfig& config);
// Reads a TOML file over `config`; unknown keys are an error, so typos do not pass silently.
Status LoadConfigFile(const std::filesystem::path& file, DaemonConfig& config);

}  // namespace pointdag::server
