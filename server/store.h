// The embedded store: one SQLite file (WAL) holding jobs, datasets, their tiles and shadow sets.
//
// Contract: a dataset and all its tiles are written in one transaction together with its job's
// "done" state, so a reader sees a dataset complete or not at all, and a crash at any point leaves
// either nothing or everything. Tiles are immutable; their strong ETag (XXH3 of the bytes) is
// computed once at commit. A dataset's shadow set (its summary and every tile's layer) is replaced
// in one transaction with its job's "done" state, so readers see the old set or the new, never a
// mix; deleting the dataset deletes its set (foreign keys, ON DELETE CASCADE). Safe to call from any thread (one connection for writes, one for reads,
// each behind its own mutex; WAL lets them proceed together).
//
// Errors: kResourceLimit when another process holds the store's lock longer than the busy timeout
// (temporary: the service answers 503 with Retry-After), kIoError for the rest (disk full, I/O). A
// read that fails is an error, never "not found".
#pragma once

#include <sqlite3.h>

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pointdag/tile/tiler.h"

namespace pointdag::server {

struct JobRecord {
  std::string id;
  std::string kind = "ingest";  // ingest (an upload), shadows (a dataset's shadow set)
  std::string state = "queued";  // queued, running, done, failed
  std::string stage = "queued";
  double percent = 0;
  uint64_t points_in = 0;
  uint64_t voxels_out = 0;
  std::string dataset_id;  // ingest: the dataset made, once done; shadows: the dataset shaded
  std::string error;
  std::string upload_path;
  int attempts = 0;  // runs started, counted before each starts: a run that crashed the process counts
  nlohmann::json params = nlohmann::json::object();  // ingest: name, voxel, epsg, quality; shadows: the request
  double created = 0, updated = 0;                    // Unix seconds
};

struct StoredTile {
  std::string etag;  // with quotes, as sent
  std::vector<uint8_t> bytes;
};

struct ShadowTile {
  TileKey key;
  uint64_t voxels = 0;
  std::vector<uint8_t> bytes;  // a layer (proto/SHADOW_FORMAT.md §2)
};

struct HierarchyEntry {
  TileKey key;
  uint64_t voxels = 0;
};

class Store {
 public:
  // How long a statement waits for another process's lock before kResourceLimit: short, so an
  // HTTP request answers 503 instead of hanging.
  static constexpr int kBusyTimeoutMs = 2000;
  // Creates the file and schema, or migrates an older store (adds jobs.attempts, jobs.kind and the
  // shadow tables; an older shadow set simply has no shadow DAG).
  static StatusOr<std::unique_ptr<Store>> Open(const std::filesystem::path& file, int busy_timeout_ms = kBusyTimeoutMs);
  ~Store();

  Status CreateJob(const JobRecord& job);
  // The job is running from now: state running, stage survey, attempts + 1 — before any work, so a
  // run that takes the process down is counted.
  Status StartAttempt(const std::string& id);
  // A running job left unfinished by a clean stop (its grace period over): not a crash, so the
  // attempt StartAttempt counted is given back; the job resumes from its upload on the next start.
  Status ReturnAttempt(const std::string& id);
  // Best effort: fails at once when another process holds the lock.
  Status UpdateJobProgress(const std::string& id, const std::string& stage, double percent, uint64_t points_in,
                           uint64_t voxels_out);
  Status SetJobState(const std::string& id, const std::string& state, const std::string& error = "");
  StatusOr<std::optional<JobRecord>> GetJob(const std::string& id);
  StatusOr<std::vector<JobRecord>> JobsInStates(const std::vector<std::string>& states);
  StatusOr<std::map<std::string, uint64_t>> JobCountsByState();

  // One transaction: the dataset row, every tile, and the job marked done with the dataset's id.
  Status CommitDataset(const std::string& job_id, const std::string& dataset_id, const std::string& name,
                       const nlohmann::json& meta, const TileSet& tiles);
  // The dataset's metadata with "shadows": its shadow set's summary, or null.
  StatusOr<std::optional<nlohmann::json>> GetDataset(const std::string& id);
  StatusOr<std::vector<nlohmann::json>> ListDatasets();
  // One transaction: the dataset and its tiles go, its job's stage becomes "deleted". False: no such dataset.
  StatusOr<bool> DeleteDataset(const std::string& id);

  StatusOr<std::optional<StoredTile>> GetTile(const std::string& dataset_id, const TileKey& key);
  // Tiles at `key` and up to `depth` levels below it; `more_below` are those of the deepest
  // level returned that have children of their own (the next pages to ask for).
  StatusOr<std::vector<HierarchyEntry>> TilesBelow(const std::string& dataset_id, const TileKey& key, int depth,
                                                   std::vector<TileKey>& more_below);

  // ---- Shadow sets (store_shadows.cc) ----
  // Creates a shadows job unless one for the same dataset is queued or running: then nothing is
  // created and that job's id is returned (one check and insert in one transaction).
  StatusOr<std::optional<std::string>> CreateShadowJob(const JobRecord& job);
  // One transaction: the dataset's shadow set (if any) goes, the new summary, every layer and the
  // serialized shadow DAG (proto/SHADOW_FORMAT.md §1; empty: the set has none) come, and the job is
  // done. kInvalidArgument when the dataset is gone (deleted meanwhile).
  Status CommitShadows(const std::string& job_id, const std::string& dataset_id, const nlohmann::json& summary,
                       const std::vector<ShadowTile>& layers, const std::vector<uint8_t>& shadow_dag);
  StatusOr<std::optional<nlohmann::json>> GetShadows(const std::string& dataset_id);
  StatusOr<std::optional<StoredTile>> GetShadowTile(const std::string& dataset_id, const TileKey& key);
  // The set's shadow DAG, or nullopt (no set, a sun-hours set, or one stored before DAGs were kept);
  // the etag alone is a cheap way to see whether a cached copy is still the current one.
  StatusOr<std::optional<StoredTile>> GetShadowDag(const std::string& dataset_id);
  StatusOr<std::optional<std::string>> GetShadowDagEtag(const std::string& dataset_id);
  // False: the dataset has no shadow set.
  StatusOr<bool> DeleteShadows(const std::string& dataset_id);

 private:
  Store() = default;
  sqlite3* writer_ = nullptr;
  sqlite3* reader_ = nullptr;
  int busy_timeout_ms_ = kBusyTimeoutMs;
  std::mutex write_mutex_, read_mutex_;
};

// A fresh random identifier: 16 lowercase hex digits.
std::string NewId();

// A tile's strong ETag: XXH3-64 of its bytes as 16 hex digits, quoted. Also its stored checksum.
std::string TileEtag(std::span<const uint8_t> bytes);

}  // namespace pointdag::server
