#include "jobs.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "pointdag/ingest.h"
#include "shadow_job.h"

namespace pointdag::server {
namespace {

// Where each stage sits in the job's overall percentage.
struct StageSpan {
  const char* name;
  double from, to;
};
constexpr StageSpan kStages[] = {{"survey", 0, 5}, {"voxelize", 5, 40}, {"tile", 40, 90}, {"compare", 90, 97}};

double OverallPercent(std::string_view stage, double fraction) {
  for (const StageSpan& s : kStages) {
    if (stage == s.name) return s.from + (s.to - s.from) * std::clamp(fraction, 0.0, 1.0);
  }
  return 0;
}

}  // namespace

nlohmann::json DescribeDataset(const std::string& id, const std::string& name, const IngestedScan& scan) {
  const VoxelGrid& g = scan.grid;
  const double side = std::ldexp(g.voxel_size, g.depth);
  uint64_t finest_bytes = 0;
  size_t tiles_finest = 0;
  for (const Tile& t : scan.tiles.tiles) {
    if (t.key.level == scan.tiles.levels - 1) finest_bytes += t.bytes.size(), ++tiles_finest;
  }
  const double voxels = static_cast<double>(g.morton.size());
  const double ours = 8.0 * static_cast<double>(finest_bytes) / voxels;
  nlohmann::json source = {{"format", ScanFormatName(scan.scan.format)}, {"version", scan.scan.format_version},
                           {"points", g.points_in}, {"has_color", g.has_color()}};
  // A LAZ source's compression and its usable COPC index: the dataset's, never in each tile.
  if (!scan.scan.compression.empty()) source["compression"] = scan.scan.compression;
  if (scan.scan.copc && scan.scan.copc->problem.empty()) {
    const auto& copc = *scan.scan.copc;
    source["copc"] = {{"nodes", copc.nodes.size()}, {"depth", copc.max_depth}, {"spacing", copc.spacing}};
  }
  return {
      {"id", id},
      {"name", name},
      {"source", source},
      {"frame", DescribeFrame(scan.frame)},
      {"units", scan.frame.georeferenced ? "metres (ENU)" : "the scan's own units"},
      {"bounds", {{"min", g.origin}, {"max", {g.origin[0] + side, g.origin[1] + side, g.origin[2] + side}}}},
      {"voxel_size", g.voxel_size},
      {"voxel_size_derived", scan.voxel_size_derived},
      {"depth", g.depth},
      {"levels", scan.tiles.levels},
      {"tile_depth", scan.tiles.tile_depth},
      {"tile_count", scan.tiles.tiles.size()},
      {"voxels", g.morton.size()},
      {"stored_bytes", scan.tiles.stored_bytes()},
      {"bits_per_point", 8.0 * static_cast<double>(scan.tiles.stored_bytes()) / static_cast<double>(g.points_in)},
      {"finest_level", {{"tiles", tiles_finest}, {"bytes", finest_bytes}, {"bits_per_voxel", ours}}},
      {"draco", {{"bits_per_point", scan.draco.bits_per_point}, {"bytes", scan.draco.bytes}, {"method", scan.draco.method},
                 {"same_voxels", true}, {"draco_over_ours", scan.draco.bits_per_point / ours}}},
      {"ingest_seconds", {{"total", scan.seconds}, {"read_georeference_voxelize", scan.voxelize_seconds},
                          {"tile", scan.tile_seconds}, {"draco", scan.compare_seconds}}},
  };
}

JobQueue::JobQueue(Store& store, Metrics& metrics, const JobLimits& limits)
    : store_(store), metrics_(metrics), limits_(limits) {
  for (int i = 0; i < std::max(1, limits.workers); ++i) workers_.emplace_back([this] { Work(); });
}

JobQueue::~JobQueue() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (auto& w : workers_) w.join();
}

void JobQueue::Resume() {
  auto jobs = store_.JobsInStates({"running", "queued"});
  if (!jobs.ok()) {
    spdlog::error("cannot resume the jobs of a previous run: {}", jobs.status().ToString());
    return;
  }
  for (const JobRecord& job : *jobs) {
    if (job.attempts >= std::max(1, limits_.max_attempts)) {
      Fail(job.id, "interrupted " + std::to_string(job.attempts) +
                       " times (the daemon stopped or crashed while running it); not retried", job.upload_path);
      continue;
    }
    if (job.kind == "ingest" && !std::filesystem::exists(job.upload_path)) {
      Fail(job.id, "the daemon stopped during this job and its upload is gone", job.upload_path);
      continue;
    }
    (void)store_.UpdateJobProgress(job.id, "resumed", 0, 0, 0);
    (void)store_.SetJobState(job.id, "queued");
    spdlog::info("job {}: resumed after a restart (started {} time(s) before)", job.id, job.attempts);
    std::lock_guard lock(mutex_);
    queue_.push_back(job.id);
  }
  wake_.notify_all();
}

bool JobQueue::Submit(const std::string& job_id) {
  {
    std::lock_guard lock(mutex_);
    if (queue_.size() >= limits_.capacity) return false;
    queue_.push_back(job_id);
  }
  wake_.notify_one();
  return true;
}

std::vector<std::string> JobQueue::Drain(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  draining_ = true;
  wake_.notify_all();
  idle_.wait_until(lock, deadline, [this] { return running_ == 0; });
  return {running_ids_.begin(), running_ids_.end()};
}

size_t JobQueue::running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

size_t JobQueue::waiting() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

std::optional<PendingEnd> JobQueue::Pending(const std::string& job_id) const {
  std::lock_guard lock(mutex_);
  const auto it = pending_.find(job_id);
  return it == pending_.end() ? std::nullopt : std::optional<PendingEnd>(it->second);
}

void JobQueue::Work() {
  constexpr auto kRetryPending = std::chrono::seconds(1);
  bool all_written = true;
  for (;;) {
    std::string id;
    {
      std::unique_lock lock(mutex_);
      const auto ready = [this] { return stopping_ || draining_ || !queue_.empty(); };
      if (all_written) {
        wake_.wait(lock, ready);
      } else if (!wake_.wait_for(lock, kRetryPending, ready)) {
        lock.unlock();
        all_written = FlushPending();
        continue;
      }
      if (stopping_ || draining_) return;
      id = queue_.front();
      queue_.pop_front();
      ++running_;
      running_ids_.insert(id);
    }
    Run(id);
    all_written = FlushPending();
    {
      std::lock_guard lock(mutex_);
      --running_;
      running_ids_.erase(id);
    }
    idle_.notify_all();
  }
}

void JobQueue::Run(const std::string& job_id) {
  auto job = store_.GetJob(job_id);
  if (!job.ok() || !*job) {
    // Nothing is known of the job but its id: it stays as the store has it (resumed at the next start).
    spdlog::error("job {}: cannot read it from the store: {}", job_id, job.ok() ? "gone" : job.status().ToString());
    return;
  }
  if (const Status s = store_.StartAttempt(job_id); !s.ok()) {
    // Running it uncounted could crash the process again and again; refuse instead.
    Fail(job_id, "cannot record the job's start in the store: " + s.ToString(), (*job)->upload_path);
    return;
  }
  std::string reason;
  // The one place a job's exceptions end (also those carried out of the tiler's parallel loops).
  try {
    reason = (*job)->kind == "shadows" ? RunShadowJob(store_, **job) : Ingest(**job);
  } catch (const std::bad_alloc&) {
    reason = "Internal: the job ran out of memory (std::bad_alloc)";
  } catch (const std::exception& e) {
    reason = std::string("Internal: the job threw an exception: ") + e.what();
  } catch (...) {
    reason = "Internal: the job threw an unknown exception";
  }
  if (!reason.empty()) {
    Fail(job_id, reason, (*job)->upload_path);
    return;
  }
  std::error_code ignored;
  if (!(*job)->upload_path.empty()) std::filesystem::remove((*job)->upload_path, ignored);  // the dataset and the done state are durable
}

std::string JobQueue::Ingest(const JobRecord& job) {
  const std::string& job_id = job.id;
  IngestOptions options;
  const auto& p = job.params;
  if (p.contains("voxel")) options.voxel_size = p["voxel"].get<double>();
  if (p.contains("epsg")) options.epsg = p["epsg"].get<int>();
  if (p.contains("quality")) options.quality_db = p["quality"].get<double>();
  options.spill_dir = limits_.spill_dir;
  options.max_points_in_memory = limits_.max_points_in_memory;
  std::mutex progress_mutex;
  int last_percent = -1;
  std::string last_stage;
  options.progress = [&](std::string_view stage, double fraction) {
    std::lock_guard lock(progress_mutex);  // tiles report from several threads
    const int percent = static_cast<int>(OverallPercent(stage, fraction));
    if (percent == last_percent && stage == last_stage) return;
    last_percent = percent;
    last_stage = stage;
    (void)store_.UpdateJobProgress(job_id, std::string(stage), percent, 0, 0);
  };
  spdlog::info("job {}: ingesting {} (attempt {})", job_id, job.upload_path, job.attempts + 1);
  auto scan = IngestScan(job.upload_path, options);
  if (!scan.ok()) return scan.status().ToString();
  (void)store_.UpdateJobProgress(job_id, "store", 97, scan->grid.points_in, scan->grid.morton.size());
  const std::string dataset_id = NewId();
  const std::string name = p.value("name", std::string("scan"));
  const Status status = store_.CommitDataset(job_id, dataset_id, name, DescribeDataset(dataset_id, name, *scan), scan->tiles);
  if (!status.ok()) return "the dataset could not be stored: " + status.ToString();
  metrics_.CountIngest(scan->grid.points_in, scan->seconds);
  spdlog::info("job {}: dataset {} ({} points, {} voxels, {} tiles, {:.2f} s)", job_id, dataset_id, scan->grid.points_in,
               scan->grid.morton.size(), scan->tiles.tiles.size(), scan->seconds);
  return "";
}

void JobQueue::Fail(const std::string& job_id, const std::string& reason, const std::string& upload_path) {
  spdlog::warn("job {}: failed: {}", job_id, reason);
  constexpr int kTries = 3;
  Status written;
  for (int attempt = 0; attempt < kTries; ++attempt) {
    if (attempt > 0) std::this_thread::sleep_for(std::chrono::milliseconds(200 * attempt));
    written = store_.SetJobState(job_id, "failed", reason);
    if (written.ok()) break;
  }
  if (written.ok()) {
    std::error_code ignored;
    std::filesystem::remove(upload_path, ignored);
    return;
  }
  spdlog::error("job {}: cannot record its failure ({}); kept in memory, written at the next chance", job_id, written.ToString());
  std::lock_guard lock(mutex_);
  pending_[job_id] = {"failed", reason, upload_path};
}

bool JobQueue::FlushPending() {
  std::map<std::string, PendingEnd> pending;
  {
    std::lock_guard lock(mutex_);
    pending = pending_;
  }
  for (const auto& [id, end] : pending) {
    if (!store_.SetJobState(id, end.state, end.error).ok()) continue;
    std::error_code ignored;
    std::filesystem::remove(end.upload_path, ignored);
    spdlog::info("job {}: its failure is recorded now", id);
    std::lock_guard lock(mutex_);
    pending_.erase(id);
  }
  std::lock_guard lock(mutex_);
  return pending_.empty();
}

}  // namespace pointdag::server
