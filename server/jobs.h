// The ingest job queue: bounded, persisted in the store, run by a pool of worker threads.
//
// Contract: Submit() refuses (returns false) when `capacity` jobs are already waiting. A job runs
// IngestScan on its upload, then commits the dataset, its tiles and the job's "done" state in one
// transaction; on failure the job is "failed" with the reason and nothing of the dataset exists.
// The upload file is removed once its job has ended either way. On start, jobs a previous process
// left queued or running are run again from their upload (state "queued", stage "resumed"), or
// failed when the upload is gone.
#pragma once

#include <condition_variable>
#include <deque>
#include <mutex>
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

class JobQueue {
 public:
  JobQueue(Store& store, Metrics& metrics, const JobLimits& limits);
  ~JobQueue();
  void Resume();
  bool Submit(const std::string& job_id);
  size_t waiting() const;
  bool full() const { return waiting() >= limits_.capacity; }
  size_t running() const;

 private:
  void Work();
  void Run(const std::string& job_id);
  Store& store_;
  Metrics& metrics_;
  JobLimits limits_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::string> queue_;
  size_t running_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

// Dataset metadata as GET /v1/datasets/{id} returns it (proto/PROTOCOL.md).
nlohmann::json DescribeDataset(const std::string& id, const std::string& name, const IngestedScan& scan);

}  // namespace pointdag::server
