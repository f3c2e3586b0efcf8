#include "nightly.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <string>
#include <vector>

#include "pointdag/bench/corpus_case.h"
#include "pointdag/bench/report.h"

extern char** environ;

namespace pointdag::server {

NightlyRunner::NightlyRunner(NightlyConfig config, Metrics& metrics)
    : config_(std::move(config)), command_(ResolveCommand(config_.command)), metrics_(metrics) {
  std::error_code ec;
  std::filesystem::create_directories(config_.reports_dir, ec);
}

std::filesystem::path NightlyRunner::ResolveCommand(const std::filesystem::path& configured) {
  if (!configured.empty()) return configured;
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec && std::filesystem::exists(self.parent_path() / "pointdag")) return self.parent_path() / "pointdag";
  return POINTDAG_BUILD_CLI;
}

std::chrono::system_clock::time_point NightlyRunner::NextRun(const NightlyConfig& config, std::chrono::system_clock::time_point now) {
  using namespace std::chrono;
  if (config.interval_s > 0) return now + seconds(config.interval_s);
  const auto day = floor<days>(now);
  auto at = day + hours(config.hour) + minutes(config.minute);
  if (at <= now) at += days(1);
  return at;
}

void NightlyRunner::Start() {
  PublishLatest(-1, 0);  // what an earlier run left
  thread_ = std::thread([this] { Loop(); });
  spdlog::info("nightly benchmark: {} with {} into {}, {}", config_.corpus.string(), command_.string(), config_.reports_dir.string(),
               config_.interval_s > 0 ? "every " + std::to_string(config_.interval_s) + " s"
                                      : fmt::format("daily at {:02}:{:02} UTC", config_.hour, config_.minute));
}

void NightlyRunner::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    if (child_ > 0) kill(child_, SIGTERM);
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void NightlyRunner::Loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    const auto next = NextRun(config_, std::chrono::system_clock::now());
    if (wake_.wait_until(lock, next, [&] { return stopping_; })) break;
    lock.unlock();
    const auto start = std::chrono::steady_clock::now();
    const int code = RunOnce();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (code == 0) {
      spdlog::info("nightly benchmark done in {:.0f} s", seconds);
    } else {
      spdlog::warn("nightly benchmark exited {} after {:.0f} s ({}: 3 is a regression; see {})", code, seconds, command_.string(),
                   (config_.reports_dir / "nightly.log").string());
    }
    PublishLatest(code, seconds);
    lock.lock();
  }
}

int NightlyRunner::RunOnce() {
  const std::string keep = std::to_string(config_.reports_kept);
  std::vector<std::string> args = {command_.string(), "bench",     "--corpus", config_.corpus.string(),
                                   "--out",           config_.reports_dir.string(), "--keep", keep};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  const std::string log = (config_.reports_dir / "nightly.log").string();
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = -1;
  int spawned = 0;
  {
    std::lock_guard lock(mutex_);
    if (stopping_) {
      posix_spawn_file_actions_destroy(&files);
      return -1;
    }
    spawned = posix_spawn(&pid, argv[0], &files, nullptr, argv.data(), environ);
    if (spawned == 0) child_ = pid;
  }
  posix_spawn_file_actions_destroy(&files);
  if (spawned != 0) {
    spdlog::error("nightly benchmark: cannot start {}: {}", command_.string(), std::strerror(spawned));
    return 127;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  std::lock_guard lock(mutex_);
  child_ = -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

void NightlyRunner::PublishLatest(int exit_code, double seconds) {
  Metrics::NightlyStatus status;
  status.last_exit_code = exit_code;
  status.last_duration_s = seconds;
  status.ran = exit_code >= 0;
  const auto reports = ListReports(config_.reports_dir);
  if (!reports.empty()) {
    if (auto report = ReadReport(reports.back()); report.ok()) {
      status.latest_report = report->value("id", "");
      for (const auto& c : (*report)["cases"]) {
        if (c.contains("error")) continue;
        const std::string scan = c.value("scan", ""), voxel = fmt::format("{}", JsonNumber(c, "voxel"));
        for (const auto& row : c.value("ours", nlohmann::json::array())) {
          status.rows.push_back({scan, voxel, CodecRowKey(row), JsonNumber(row, "bits_per_point")});
        }
        status.rows.push_back({scan, voxel, "draco", JsonNumber(c, "draco_bits_per_point")});
      }
    }
  }
  metrics_.SetNightly(std::move(status));
}

}  // namespace pointdag::server
