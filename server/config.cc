#include "config.h"

#include <toml++/toml.h>

#include <charconv>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace pointdag::server {
namespace {

// One TOML table read key by key; every key read is marked, so the rest are unknown.
class Reader {
 public:
  Reader(const toml::table& table, const std::string& origin) : table_(table), origin_(origin) {}

  template <typename T>
  Status Int(const char* key, T& out, int64_t min, int64_t max) {
    const toml::node* node = Find(key);
    if (!node) return Status::Ok();
    const auto value = node->value_exact<int64_t>();
    if (!value) return Wrong(key, "an integer");
    if (*value < min || *value > max) {
      return InvalidArgument(origin_ + ": " + key + " must be between " + std::to_string(min) + " and " + std::to_string(max));
    }
    out = static_cast<T>(*value);
    return Status::Ok();
  }
  Status String(const char* key, std::string& out) {
    const toml::node* node = Find(key);
    if (!node) return Status::Ok();
    const auto value = node->value_exact<std::string>();
    if (!value) return Wrong(key, "a string");
    out = *value;
    return Status::Ok();
  }
  Status Bool(const char* key, bool& out) {
    const toml::node* node = Find(key);
    if (!node) return Status::Ok();
    const auto value = node->value_exact<bool>();
    if (!value) return Wrong(key, "true or false");
    out = *value;
    return Status::Ok();
  }
  Status Strings(const char* key, std::vector<std::string>& out) {
    const toml::node* node = Find(key);
    if (!node) return Status::Ok();
    const toml::array* array = node->as_array();
    if (!array || array->empty()) return Wrong(key, "a non-empty array of strings");
    std::vector<std::string> values;
    for (const toml::node& item : *array) {
      const auto value = item.value_exact<std::string>();
      if (!value) return Wrong(key, "a non-empty array of strings");
      values.push_back(*value);
    }
    out = std::move(values);
    return Status::Ok();
  }
  // A sub-table ([nightly]); null when absent.
  StatusOr<const toml::table*> Table(const char* key) {
    const toml::node* node = Find(key);
    if (!node) return static_cast<const toml::table*>(nullptr);
    if (!node->as_table()) return Wrong(key, "a table");
    return node->as_table();
  }
  Status CheckAllRead() const {
    for (const auto& [key, value] : table_) {
      if (!read_.count(std::string(key.str()))) return InvalidArgument(origin_ + ": unknown key '" + std::string(key.str()) + "'");
    }
    return Status::Ok();
  }

 private:
  const toml::node* Find(const char* key) {
    read_.insert(key);
    return table_.get(key);
  }
  Status Wrong(const char* key, const char* what) const { return InvalidArgument(origin_ + ": " + key + " must be " + what); }

  const toml::table& table_;
  const std::string& origin_;
  std::set<std::string> read_;
};

constexpr int64_t kInt = std::numeric_limits<int>::max();
constexpr int64_t kHour = 3600;

Status ParseNightly(const toml::table& table, NightlyConfig& nightly, const std::string& origin) {
  Reader r(table, origin);
  std::string corpus, reports_dir, command, time;
  RETURN_IF_ERROR(r.String("corpus", corpus));
  if (corpus.empty()) return InvalidArgument(origin + ": corpus is required (a corpus TOML file or a folder of scans)");
  nightly.corpus = corpus;
  RETURN_IF_ERROR(r.String("time", time));
  if (!time.empty()) {
    const auto two_digits = [&](size_t at, int max) {
      int v = 0;
      const auto [end, ec] = std::from_chars(time.data() + at, time.data() + at + 2, v);
      return ec == std::errc() && end == time.data() + at + 2 && v >= 0 && v <= max ? v : -1;
    };
    const int hour = time.size() == 5 && time[2] == ':' ? two_digits(0, 23) : -1;
    const int minute = time.size() == 5 && time[2] == ':' ? two_digits(3, 59) : -1;
    if (hour < 0 || minute < 0) return InvalidArgument(origin + ": time must be \"HH:MM\" (UTC), got '" + time + "'");
    nightly.hour = hour;
    nightly.minute = minute;
  }
  RETURN_IF_ERROR(r.Int("interval_s", nightly.interval_s, 0, 366 * 24 * kHour));
  RETURN_IF_ERROR(r.Int("reports_kept", nightly.reports_kept, 1, 100000));
  RETURN_IF_ERROR(r.String("reports_dir", reports_dir));
  if (!reports_dir.empty()) nightly.reports_dir = reports_dir;
  RETURN_IF_ERROR(r.String("command", command));
  if (!command.empty()) nightly.command = command;
  return r.CheckAllRead();
}

}  // namespace

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

Status ParseConfigText(std::string_view text, DaemonConfig& config, const std::string& origin) {
  toml::table table;
  try {
    table = toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    return InvalidArgument(origin + ": " + std::string(e.description()));
  }
  Reader r(table, origin);
  std::string listen, data_dir, token_file;
  RETURN_IF_ERROR(r.String("listen", listen));
  if (!listen.empty()) RETURN_IF_ERROR(ParseListen(listen, config));
  RETURN_IF_ERROR(r.String("data_dir", data_dir));
  if (!data_dir.empty()) config.data_dir = data_dir;
  RETURN_IF_ERROR(r.String("token", config.token));
  RETURN_IF_ERROR(r.String("token_file", token_file));
  if (!token_file.empty()) config.token_file = token_file;
  RETURN_IF_ERROR(r.String("read_token", config.read_token));
  RETURN_IF_ERROR(r.Bool("require_token_for_reads", config.require_token_for_reads));
  RETURN_IF_ERROR(r.Int("workers", config.workers, 1, 256));
  RETURN_IF_ERROR(r.Int("http_threads", config.http_threads, 1, 256));
  RETURN_IF_ERROR(r.Int("queue_size", config.queue_size, 1, 1 << 20));
  RETURN_IF_ERROR(r.Int("max_attempts", config.max_attempts, 1, 100));
  RETURN_IF_ERROR(r.Int("shutdown_grace_s", config.shutdown_grace_s, 0, 24 * kHour));
  RETURN_IF_ERROR(r.Int("max_upload_bytes", config.max_upload_bytes, 1, std::numeric_limits<int64_t>::max()));
  RETURN_IF_ERROR(r.Int("tile_cache_mb", config.tile_cache_mb, 0, 1 << 20));
  RETURN_IF_ERROR(r.Int("tiles3d_cache_mb", config.tiles3d_cache_mb, 0, 1 << 20));
  RETURN_IF_ERROR(r.Strings("cors_origins", config.cors_origins));
  std::string web_dir = config.web_dir.string();
  RETURN_IF_ERROR(r.String("web_dir", web_dir));
  config.web_dir = web_dir;  // "" turns the viewer off
  RETURN_IF_ERROR(r.String("log_level", config.log_level));
  static const std::set<std::string> levels = {"trace", "debug", "info", "warn", "error", "critical", "off"};
  if (!levels.count(config.log_level)) return InvalidArgument(origin + ": log_level must be trace, debug, info, warn, error, critical or off");
  HttpLimits& h = config.http;
  RETURN_IF_ERROR(r.Int("max_connections", h.max_connections, 1, 1 << 20));
  RETURN_IF_ERROR(r.Int("max_connections_per_client", h.max_connections_per_client, 1, 1 << 20));
  RETURN_IF_ERROR(r.Int("max_uploads", h.max_uploads, 1, 1 << 16));
  RETURN_IF_ERROR(r.Int("header_timeout_s", h.header_timeout_s, 1, kHour));
  RETURN_IF_ERROR(r.Int("idle_timeout_s", h.idle_timeout_s, 1, kHour));
  RETURN_IF_ERROR(r.Int("body_timeout_s", h.body_timeout_s, 1, kHour));
  RETURN_IF_ERROR(r.Int("write_timeout_s", h.write_timeout_s, 1, kHour));
  RETURN_IF_ERROR(r.Int("max_header_bytes", h.max_header_bytes, 1024, 1 << 20));
  RETURN_IF_ERROR(r.Int("max_header_fields", h.max_header_fields, 8, 10000));
  RETURN_IF_ERROR(r.Int("upload_min_rate", h.upload_min_rate, 0, kInt));
  RETURN_IF_ERROR(r.Int("upload_rate_window_s", h.upload_rate_window_s, 1, kHour));
  int64_t reserve_mb = static_cast<int64_t>(h.disk_reserve_bytes >> 20);
  RETURN_IF_ERROR(r.Int("disk_reserve_mb", reserve_mb, 0, int64_t{1} << 30));
  h.disk_reserve_bytes = static_cast<uint64_t>(reserve_mb) << 20;
  RETURN_IF_ERROR(r.Int("check_threads", h.check_threads, 1, 64));
  ASSIGN_OR_RETURN(const toml::table* nightly, r.Table("nightly"));
  if (nightly) RETURN_IF_ERROR(ParseNightly(*nightly, config.nightly, origin + " [nightly]"));
  return r.CheckAllRead();
}

Status LoadConfigFile(const std::filesystem::path& file, DaemonConfig& config) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return IoError("cannot read " + file.string());
  std::ostringstream text;
  text << in.rdbuf();
  return ParseConfigText(text.str(), config, file.string());
}

}  // namespace pointdag::server
