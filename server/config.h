// pointdagd's configuration: the embedded defaults, then a TOML file (toml++), then the
// environment (tokens), then flags (CLI11). configs/pointdagd.toml documents every key.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "pointdag/status.h"

namespace pointdag::server {

// What one connection may cost the daemon, phase by phase (http_server.cc).
struct HttpLimits {
  int max_connections = 1024;          // beyond it a new connection gets 503 and is closed
  int max_connections_per_client = 256;  // per remote address, so one client cannot take them all
  int max_uploads = 4;                 // uploads streaming at once; beyond it 503 + Retry-After
  int header_timeout_s = 30;           // from a request's first byte to the end of its header
  int idle_timeout_s = 60;             // keep-alive: waiting for the next request's first byte
  int body_timeout_s = 30;             // a small (non-upload) request body
  int write_timeout_s = 60;            // writing one response (a client that does not read it)
  uint32_t max_header_bytes = 16 * 1024;
  uint32_t max_header_fields = 100;
  uint64_t upload_min_rate = 16 * 1024;  // bytes/s an upload must keep, measured over the window
  int upload_rate_window_s = 30;
  uint64_t disk_reserve_bytes = uint64_t{256} << 20;  // free space an upload must leave on the data disk
  int check_threads = 2;               // threads that check uploads (off the HTTP threads)
};

// [nightly]: the compression benchmark on a schedule (server/nightly.h, docs/nightly.md).
struct NightlyConfig {
  std::filesystem::path corpus;        // empty: no schedule
  int hour = 3, minute = 15;           // "time" = "HH:MM", UTC, once a day
  int interval_s = 0;                  // > 0: every interval_s seconds instead (tests, staging)
  size_t reports_kept = 30;
  std::filesystem::path reports_dir;   // empty: data_dir/reports
  std::filesystem::path command;       // the pointdag CLI; empty: beside pointdagd, else the build's
};

struct DaemonConfig {
  std::string host = "127.0.0.1";
  uint16_t port = 8080;
  std::filesystem::path data_dir = "./var";
  std::string token;                      // write scope; empty: no token needed for writes
  std::filesystem::path token_file;       // the token read from a file instead (first line)
  std::string read_token;                 // read scope only
  bool require_token_for_reads = false;
  int workers = 1;                        // ingest threads (each also uses the tile encoder's threads)
  int http_threads = 2;                   // threads serving HTTP
  size_t queue_size = 16;                 // jobs waiting beyond the running ones
  int max_attempts = 2;                   // a job that failed or crashed this often is not resumed
  int shutdown_grace_s = 8;               // SIGTERM: running jobs may finish within it (docker stop waits 10 s)
  uint64_t max_upload_bytes = uint64_t{4} << 30;
  size_t tile_cache_mb = 256;
  size_t tiles3d_cache_mb = 256;          // transcoded 3D Tiles (tilesets and .glb contents)
  std::vector<std::string> cors_origins{"*"};
  std::string log_level = "info";
  std::filesystem::path port_file;        // where to write the bound port (for --listen HOST:0)
  std::filesystem::path web_dir = POINTDAG_DEFAULT_WEB_DIR;  // the viewer (web/build.mjs output); empty: none
  HttpLimits http;
  NightlyConfig nightly;
};

// "HOST:PORT" -> host and port.
Status ParseListen(const std::string& listen, DaemonConfig& config);
// Reads TOML text over `config`; unknown keys, wrong types and out-of-range values are errors, so
// typos do not pass silently. `origin` names the text in messages.
Status ParseConfigText(std::string_view text, DaemonConfig& config, const std::string& origin = "config");
Status LoadConfigFile(const std::filesystem::path& file, DaemonConfig& config);

}  // namespace pointdag::server
