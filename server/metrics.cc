#include "metrics.h"

#include <chrono>
#include <sstream>

namespace pointdag::server {
namespace {
constexpr const char* kBucketLabels[] = {"0.0005", "0.001", "0.0025", "0.005", "0.01", "0.025", "0.05", "0.1", "0.25", "0.5", "1", "5"};

// A label value in the text exposition: backslash, double quote and newline escaped.
std::string LabelValue(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\\' || c == '"') out += '\\';
    out += c == '\n' ? std::string("\\n") : std::string(1, c);
  }
  return out;
}
}  // namespace

void Metrics::CountRequest(const std::string& route, int status, double seconds, uint64_t body_bytes) {
  std::lock_guard lock(mutex_);
  ++requests_[{route, status}];
  auto& buckets = latency_[route];
  size_t b = 0;
  while (b < kBuckets.size() && seconds > kBuckets[b]) ++b;
  ++buckets[b];
  latency_sum_[route] += seconds;
  bytes_served_ += body_bytes;
}

void Metrics::CountIngest(uint64_t points, double seconds) {
  std::lock_guard lock(mutex_);
  ingest_points_ += points;
  ingest_seconds_ += seconds;
  if (seconds > 0) last_ingest_points_per_s_ = static_cast<double>(points) / seconds;
}

void Metrics::CountCorruptTile() {
  std::lock_guard lock(mutex_);
  ++corrupt_tiles_;
}

void Metrics::SetStageDevices(std::vector<StageDevice> stages) {
  std::lock_guard lock(mutex_);
  stages_ = std::move(stages);
}

void Metrics::SetNightly(NightlyStatus status) {
  std::lock_guard lock(mutex_);
  nightly_enabled_ = true;
  if (status.ran) {
    ++nightly_runs_;
    nightly_last_run_unix_ = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  } else {
    status.last_exit_code = nightly_.last_exit_code;
  }
  nightly_ = std::move(status);
}

void Metrics::RenderNightly(std::ostringstream& out) const {
  out << "# HELP pointdag_nightly_runs_total Nightly benchmark runs finished since start.\n# TYPE pointdag_nightly_runs_total counter\n"
      << "pointdag_nightly_runs_total " << nightly_runs_ << "\n"
      << "# HELP pointdag_nightly_last_exit_code Exit code of the last run (0 ok, 1 error, 3 regression; -1 none yet).\n"
      << "# TYPE pointdag_nightly_last_exit_code gauge\npointdag_nightly_last_exit_code " << nightly_.last_exit_code << "\n"
      << "# HELP pointdag_nightly_last_run_timestamp_seconds When the last run finished (Unix time; 0 none since start).\n"
      << "# TYPE pointdag_nightly_last_run_timestamp_seconds gauge\npointdag_nightly_last_run_timestamp_seconds "
      << nightly_last_run_unix_ << "\n"
      << "# HELP pointdag_nightly_last_duration_seconds Wall time of the last run.\n"
      << "# TYPE pointdag_nightly_last_duration_seconds gauge\npointdag_nightly_last_duration_seconds " << nightly_.last_duration_s << "\n"
      << "# HELP pointdag_nightly_bits_per_point The newest report's bits per point (geometry and colors), by scan, voxel and codec.\n"
      << "# TYPE pointdag_nightly_bits_per_point gauge\n";
  for (const auto& row : nightly_.rows) {
    out << "pointdag_nightly_bits_per_point{report=\"" << LabelValue(nightly_.latest_report) << "\",scan=\"" << LabelValue(row.scan)
        << "\",voxel=\"" << LabelValue(row.voxel) << "\",codec=\"" << LabelValue(row.codec) << "\"} " << row.bits_per_point << "\n";
  }
}

std::string Metrics::Render(const std::map<std::string, uint64_t>& jobs_by_state) const {
  std::lock_guard lock(mutex_);
  std::ostringstream out;
  out << "# HELP pointdag_http_requests_total HTTP requests answered, by route and status.\n"
      << "# TYPE pointdag_http_requests_total counter\n";
  for (const auto& [key, n] : requests_) {
    out << "pointdag_http_requests_total{route=\"" << key.first << "\",status=\"" << key.second << "\"} " << n << "\n";
  }
  out << "# HELP pointdag_http_request_duration_seconds Time from a request's header to its response, by route.\n"
      << "# TYPE pointdag_http_request_duration_seconds histogram\n";
  for (const auto& [route, buckets] : latency_) {
    uint64_t cumulative = 0;
    for (size_t b = 0; b <= kBuckets.size(); ++b) {
      cumulative += buckets[b];
      out << "pointdag_http_request_duration_seconds_bucket{route=\"" << route << "\",le=\""
          << (b < kBuckets.size() ? kBucketLabels[b] : "+Inf")
          << "\"} " << cumulative << "\n";
    }
    out << "pointdag_http_request_duration_seconds_sum{route=\"" << route << "\"} " << latency_sum_.at(route) << "\n"
        << "pointdag_http_request_duration_seconds_count{route=\"" << route << "\"} " << cumulative << "\n";
  }
  out << "# HELP pointdag_http_response_bytes_total Response body bytes sent.\n"
      << "# TYPE pointdag_http_response_bytes_total counter\n"
      << "pointdag_http_response_bytes_total " << bytes_served_ << "\n"
      << "# HELP pointdag_corrupt_tiles_total Tile reads refused because the stored bytes do not match their checksum.\n"
      << "# TYPE pointdag_corrupt_tiles_total counter\n"
      << "pointdag_corrupt_tiles_total " << corrupt_tiles_ << "\n"
      << "# HELP pointdag_jobs Ingest jobs by state.\n# TYPE pointdag_jobs gauge\n";
  for (const auto& [state, n] : jobs_by_state) out << "pointdag_jobs{state=\"" << state << "\"} " << n << "\n";
  out << "# HELP pointdag_ingest_points_total Input points of finished ingests.\n# TYPE pointdag_ingest_points_total counter\n"
      << "pointdag_ingest_points_total " << ingest_points_ << "\n"
      << "# HELP pointdag_ingest_seconds_total Wall time of finished ingests.\n# TYPE pointdag_ingest_seconds_total counter\n"
      << "pointdag_ingest_seconds_total " << ingest_seconds_ << "\n"
      << "# HELP pointdag_ingest_points_per_second End-to-end throughput of the last finished ingest.\n"
      << "# TYPE pointdag_ingest_points_per_second gauge\n"
      << "pointdag_ingest_points_per_second " << last_ingest_points_per_s_ << "\n"
      << "# HELP pointdag_stage_device Where each heavy stage runs (1 on the device named), decided at start.\n"
      << "# TYPE pointdag_stage_device gauge\n";
  for (const StageDevice& s : stages_) out << "pointdag_stage_device{stage=\"" << s.stage << "\",device=\"" << LabelValue(s.device) << "\"} 1\n";
  out << "# HELP pointdag_stage_calibration_seconds Time of each path on the stage's calibration input at start.\n"
      << "# TYPE pointdag_stage_calibration_seconds gauge\n";
  for (const StageDevice& s : stages_) {
    if (s.cpu_seconds <= 0) continue;
    out << "pointdag_stage_calibration_seconds{stage=\"" << s.stage << "\",path=\"cpu\"} " << s.cpu_seconds << "\n"
        << "pointdag_stage_calibration_seconds{stage=\"" << s.stage << "\",path=\"vulkan\"} " << s.vulkan_seconds << "\n";
  }
  if (nightly_enabled_) RenderNightly(out);
  return out.str();
}

}  // namespace pointdag::server
