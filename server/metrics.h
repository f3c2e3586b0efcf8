// Prometheus text exposition (version 0.0.4) of what the daemon does: requests by route and status,
// a latency histogram, bytes served, jobs by state, ingest throughput.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace pointdag::server {

class Metrics {
 public:
  void CountRequest(const std::string& route, int status, double seconds, uint64_t body_bytes);
  void CountIngest(uint64_t points, double seconds);
  // A tile whose stored bytes no longer match their checksum (answered 500, never served).
  void CountCorruptTile();
  // Where each heavy stage runs, decided at start: stage -> device ("cpu" or a Vulkan device's name),
  // with the calibration's seconds per path where it was measured.
  struct StageDevice {
    std::string stage, device;
    double cpu_seconds = 0, vulkan_seconds = 0;
  };
  void SetStageDevices(std::vector<StageDevice> stages);
  // The nightly benchmark (nightly.h): its last run, and the newest report's bits per point per
  // scan, voxel size and codec row ("vbr@38", "lossless", "draco").
  struct NightlyStatus {
    bool ran = false;  // a run just finished (false: the state found at start)
    int last_exit_code = -1;
    double last_duration_s = 0;
    std::string latest_report;
    struct Row {
      std::string scan, voxel, codec;
      double bits_per_point = 0;
    };
    std::vector<Row> rows;
  };
  void SetNightly(NightlyStatus status);
  std::string Render(const std::map<std::string, uint64_t>& jobs_by_state) const;

 private:
  void RenderNightly(std::ostringstream& out) const;  // under mutex_
  static constexpr std::array<double, 12> kBuckets = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 5};
  mutable std::mutex mutex_;
  std::map<std::pair<std::string, int>, uint64_t> requests_;
  std::map<std::string, std::array<uint64_t, kBuckets.size() + 1>> latency_;  // per route; last = +Inf
  std::map<std::string, double> latency_sum_;
  uint64_t bytes_served_ = 0;
  uint64_t corrupt_tiles_ = 0;
  uint64_t ingest_points_ = 0;
  double ingest_seconds_ = 0;
  double last_ingest_points_per_s_ = 0;
  std::vector<StageDevice> stages_;
  bool nightly_enabled_ = false;
  uint64_t nightly_runs_ = 0;
  double nightly_last_run_unix_ = 0;
  NightlyStatus nightly_;
};

}  // namespace pointdag::server
