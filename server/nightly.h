// pointdagd's [nightly] schedule (docs/nightly.md): once a day at a UTC time (or every interval_s),
// runs the pointdag CLI's `bench --corpus CORPUS --out REPORTS --keep N` as a child process, so a
// crash or a leak in a benchmark case never touches the daemon; its output goes to
// REPORTS/nightly.log. Never two runs at once; Stop() sends a running child SIGTERM and waits (the
// CLI writes its reports atomically, so a stopped run leaves nothing half-written). After every run,
// and at start, the newest report's sizes go to /metrics.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>

#include "config.h"
#include "metrics.h"

namespace pointdag::server {

class NightlyRunner {
 public:
  // `config.reports_dir` must be set (main: data_dir/reports by default); it is created.
  NightlyRunner(NightlyConfig config, Metrics& metrics);
  ~NightlyRunner() { Stop(); }
  NightlyRunner(const NightlyRunner&) = delete;
  NightlyRunner& operator=(const NightlyRunner&) = delete;

  void Start();
  void Stop();

  // The CLI the daemon runs: `configured` when set, else `pointdag` beside this executable, else
  // the one this build made.
  static std::filesystem::path ResolveCommand(const std::filesystem::path& configured);
  // The next run strictly after `now`.
  static std::chrono::system_clock::time_point NextRun(const NightlyConfig& config, std::chrono::system_clock::time_point now);

 private:
  void Loop();
  int RunOnce();
  void PublishLatest(int exit_code, double seconds);

  NightlyConfig config_;
  std::filesystem::path command_;
  Metrics& metrics_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  pid_t child_ = -1;
};

}  // namespace pointdag::server
