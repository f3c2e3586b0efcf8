// The job queue: bounded, persisted in the store, run by a pool of worker threads. Most jobs are
// ingests (below); a "shadows" job computes a dataset's shadow set instead (shadow_job.h), has no
// upload, and otherwise follows the same rules (counted starts, resumed after a restart, failures).
//
// Contract: Submit() refuses (returns false) when `capacity` jobs are already waiting. A job runs
// IngestScan on its upload, then commits the dataset, its tiles and the job's "done" state in one
// transaction; on failure the job is "failed" with the reason and nothing of the dataset exists.
// The upload file is removed once its job's end state is durable in the store, never before. A job
// that throws (a bug, bad_alloc) is failed with the reason; nothing a job does takes the process
// down by an exception. When the end state cannot be written (disk full, the store locked by
// another process), it is retried, then kept in memory — PendingEnd() reports it — and written at
// the next chance; until then the upload stays, so a restart runs the job again.
//
// On start, Resume() runs again the jobs a previous process left queued or running, from their
// upload (state "queued", stage "resumed"); it fails those whose upload is gone and those already
// started `max_attempts` times (each start is counted in the store before the job runs, so a run
// that crashed the process counts), and removes uploads no such job references (left by a crash
// mid-upload).
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <vector>

#include "metrics.h"
#include "pointdag/ingest.h"
#include "store.h"

namespace pointdag::server {

struct JobLimits {
  int workers = 1;
  size_t capacity = 16;
  std::filesystem::path spill_dir;
  uint64_t max_points_in_memory = uint64_t{1} << 25;
  int max_attempts = 2;  // a job that failed or took the process down this often is not resumed again
};

// A job's end the store has not recorded yet.
struct PendingEnd {
  std::string state;  // "failed"
  std::string error;
  std::string upload_path;  // removed once the end is durable
};

class JobQueue {
 public:
  JobQueue(Store& store, Metrics& metrics, const JobLimits& limits);
  ~JobQueue();
  void Resume();
  bool Submit(const std::string& job_id);
  size_t waiting() const;
  bool full() const { return waiting() >= limits_.capacity; }
  size_t running() const;
  // A clean stop: no queued job starts any more; waits until the running ones end or `deadline`
  // passes. Returns the ids of those still running then (their ingests cannot be cut short).
  std::vector<std::string> Drain(std::chrono::steady_clock::time_point deadline);
  // The end of a job that the store could not record yet, if any: the truth about that job.
  std::optional<PendingEnd> Pending(const std::string& job_id) const;

 private:
  void Work();
  void Run(const std::string& job_id);
  // Ingests and commits; a failure's reason, or "" when the dataset is committed.
  std::string Ingest(const JobRecord& job);
  // Records a failed end (retried; kept in memory when the store refuses) and removes the upload once durable.
  void Fail(const std::string& job_id, const std::string& reason, const std::string& upload_path);
  // Writes the ends kept in memory; true when none is left.
  bool FlushPending();
  Store& store_;
  Metrics& metrics_;
  JobLimits limits_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::string> queue_;
  size_t running_ = 0;
  std::set<std::string> running_ids_;
  std::condition_variable idle_;  // running_ fell
  bool stopping_ = false;
  bool draining_ = false;
  std::map<std::string, PendingEnd> pending_;
  std::vector<std::thread> workers_;
};

// Dataset metadata as GET /v1/datasets/{id} returns it (proto/PROTOCOL.md).
nlohmann::json DescribeDataset(const std::string& id, const std::string& name, const IngestedScan& scan);

}  // namespace pointdag::server
