#include "jobs.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>

#include "pointdag/ingest.h"

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
  for (const JobRecord& job : store_.JobsInStates({"running", "queued"})) {
    if (!std::filesystem::exists(job.upload_path)) {
      (void)store_.SetJobState(job.id, "failed", "the daemon stopped during this job and its upload is gone");
      continue;
    }
    (void)store_.UpdateJobProgress(job.id, "resumed", 0, 0, 0);
    (void)store_.SetJobState(job.id, "queued");
    spdlog::info("job {}: resumed after a restart", job.id);
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

size_t JobQueue::running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

size_t JobQueue::waiting() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

void JobQueue::Work() {
  for (;;) {
    std::string id;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      id = queue_.front();
      queue_.pop_front();
      ++running_;
    }
    Run(id);
    std::lock_guard lock(mutex_);
    --running_;
  }
}

void JobQueue::Run(const std::string& job_id) {
  const auto job = store_.GetJob(job_id);
  if (!job) return;
  IngestOptions options;
  const auto& p = job->params;
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
  (void)store_.UpdateJobProgress(job_id, "survey", 0, 0, 0);
  spdlog::info("job {}: ingesting {}", job_id, job->upload_path);
  auto scan = IngestScan(job->upload_path, options);
  Status status = scan.status();
  if (status.ok()) {
    (void)store_.UpdateJobProgress(job_id, "store", 97, scan->grid.points_in, scan->grid.morton.size());
    const std::string dataset_id = NewId();
    const std::string name = p.value("name", std::string("scan"));
    status = store_.CommitDataset(job_id, dataset_id, name, DescribeDataset(dataset_id, name, *scan), scan->tiles);
    if (status.ok()) {
      metrics_.CountIngest(scan->grid.points_in, scan->seconds);
      spdlog::info("job {}: dataset {} ({} points, {} voxels, {} tiles, {:.2f} s)", job_id, dataset_id,
                   scan->grid.points_in, scan->grid.morton.size(), scan->tiles.tiles.size(), scan->seconds);
    }
  }
  if (!status.ok()) {
    spdlog::warn("job {}: failed: {}", job_id, status.ToString());
    (void)store_.SetJobState(job_id, "failed", status.ToString());
  }
  std::error_code ignored;
  std::filesystem::remove(job->upload_path, ignored);
}

}  // namespace pointdag::server
