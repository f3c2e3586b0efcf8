#include "store.h"

#include <xxhash.h>

#include <chrono>
#include <cstdio>
#include <random>

#include "pointdag/json_text.h"
#include "sqlite_util.h"

namespace pointdag::server {
namespace {

double Now() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  id TEXT PRIMARY KEY, state TEXT NOT NULL, stage TEXT NOT NULL, percent REAL NOT NULL,
  points_in INTEGER NOT NULL, voxels_out INTEGER NOT NULL, dataset_id TEXT NOT NULL, error TEXT NOT NULL,
  upload_path TEXT NOT NULL, params TEXT NOT NULL, created REAL NOT NULL, updated REAL NOT NULL,
  attempts INTEGER NOT NULL DEFAULT 0, kind TEXT NOT NULL DEFAULT 'ingest');
CREATE TABLE IF NOT EXISTS datasets (
  id TEXT PRIMARY KEY, name TEXT NOT NULL, created REAL NOT NULL, meta TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS tiles (
  dataset_id TEXT NOT NULL REFERENCES datasets(id) ON DELETE CASCADE,
  level INTEGER NOT NULL, x INTEGER NOT NULL, y INTEGER NOT NULL, z INTEGER NOT NULL,
  voxels INTEGER NOT NULL, etag TEXT NOT NULL, bytes BLOB NOT NULL,
  PRIMARY KEY (dataset_id, level, x, y, z));
CREATE TABLE IF NOT EXISTS shadow_sets (
  dataset_id TEXT PRIMARY KEY REFERENCES datasets(id) ON DELETE CASCADE,
  job_id TEXT NOT NULL, created REAL NOT NULL, summary TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS shadow_tiles (
  dataset_id TEXT NOT NULL REFERENCES shadow_sets(dataset_id) ON DELETE CASCADE,
  level INTEGER NOT NULL, x INTEGER NOT NULL, y INTEGER NOT NULL, z INTEGER NOT NULL,
  voxels INTEGER NOT NULL, etag TEXT NOT NULL, bytes BLOB NOT NULL,
  PRIMARY KEY (dataset_id, level, x, y, z));
CREATE TABLE IF NOT EXISTS shadow_dags (
  dataset_id TEXT PRIMARY KEY REFERENCES shadow_sets(dataset_id) ON DELETE CASCADE,
  etag TEXT NOT NULL, bytes BLOB NOT NULL);
)sql";

// Stores written before jobs.attempts existed get the column (their jobs count as never started);
// before jobs.kind, theirs are all ingests.
Status Migrate(sqlite3* db) {
  for (const auto& [column, sql] : {std::pair{"attempts", "ALTER TABLE jobs ADD COLUMN attempts INTEGER NOT NULL DEFAULT 0"},
                                    std::pair{"kind", "ALTER TABLE jobs ADD COLUMN kind TEXT NOT NULL DEFAULT 'ingest'"}}) {
    Statement columns(db, "SELECT 1 FROM pragma_table_info('jobs') WHERE name = ?");
    ASSIGN_OR_RETURN(const bool has_column, columns.Bind(column).Next());
    if (!has_column) RETURN_IF_ERROR(Exec(db, sql));
  }
  return Status::Ok();
}

StatusOr<sqlite3*> OpenConnection(const std::filesystem::path& file, int busy_timeout_ms) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK) {
    std::string message = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    return IoError("cannot open the store " + file.string() + ": " + message);
  }
  sqlite3_busy_timeout(db, busy_timeout_ms);
  return db;
}

JobRecord ReadJob(const Statement& s) {
  JobRecord j;
  j.id = s.Text(0);
  j.state = s.Text(1);
  j.stage = s.Text(2);
  j.percent = s.Real(3);
  j.points_in = static_cast<uint64_t>(s.Int(4));
  j.voxels_out = static_cast<uint64_t>(s.Int(5));
  j.dataset_id = s.Text(6);
  j.error = s.Text(7);
  j.upload_path = s.Text(8);
  auto params = ParseJson(s.Text(9));
  j.params = params.ok() ? std::move(*params) : nlohmann::json();  // the job reports what it cannot use
  j.created = s.Real(10);
  j.updated = s.Real(11);
  j.attempts = static_cast<int>(s.Int(12));
  j.kind = s.Text(13);
  return j;
}

constexpr const char* kJobColumns =
    "SELECT id, state, stage, percent, points_in, voxels_out, dataset_id, error, upload_path, params, created, updated, "
    "attempts, kind FROM jobs";

// Dataset metadata as stored; a row that is not JSON is reported, not thrown.
StatusOr<nlohmann::json> ParseMeta(const std::string& text) {
  auto meta = ParseJson(text);
  if (!meta.ok()) return Corrupt("a dataset's stored metadata is not JSON: " + meta.status().message());
  return meta;
}

// A dataset's metadata with its shadow set's summary (or null): the columns ReadDataset() takes.
constexpr const char* kDatasetColumns =
    "SELECT d.meta, s.summary FROM datasets d LEFT JOIN shadow_sets s ON s.dataset_id = d.id";

StatusOr<nlohmann::json> ReadDataset(const Statement& s) {
  ASSIGN_OR_RETURN(nlohmann::json meta, ParseMeta(s.Text(0)));
  meta["shadows"] = nullptr;
  if (!s.IsNull(1)) {
    auto summary = ParseJson(s.Text(1));
    if (!summary.ok()) return Corrupt("a dataset's stored shadow summary is not JSON: " + summary.status().message());
    meta["shadows"] = std::move(*summary);
  }
  return meta;
}

}  // namespace

std::string NewId() {
  static thread_local std::mt19937_64 rng(std::random_device{}());
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(rng()));
  return hex;
}

std::string TileEtag(std::span<const uint8_t> bytes) {
  char hex[40];
  std::snprintf(hex, sizeof(hex), "\"%016llx\"", static_cast<unsigned long long>(XXH3_64bits(bytes.data(), bytes.size())));
  return hex;
}

StatusOr<std::unique_ptr<Store>> Store::Open(const std::filesystem::path& file, int busy_timeout_ms) {
  std::unique_ptr<Store> store(new Store());
  store->busy_timeout_ms_ = busy_timeout_ms;
  ASSIGN_OR_RETURN(store->writer_, OpenConnection(file, busy_timeout_ms));
  RETURN_IF_ERROR(Exec(store->writer_, "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON;"));
  RETURN_IF_ERROR(Exec(store->writer_, kSchema));
  RETURN_IF_ERROR(Migrate(store->writer_));
  ASSIGN_OR_RETURN(store->reader_, OpenConnection(file, busy_timeout_ms));
  return store;
}

Store::~Store() {
  sqlite3_close(reader_);
  sqlite3_close(writer_);
}

Status Store::CreateJob(const JobRecord& job) {
  std::lock_guard lock(write_mutex_);
  Statement s(writer_,
              "INSERT INTO jobs (id, state, stage, percent, points_in, voxels_out, dataset_id, error, upload_path, params, "
              "created, updated, attempts, kind) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
  const double now = Now();
  return s.Bind(job.id, job.state, job.stage, job.percent, job.points_in, job.voxels_out, job.dataset_id, job.error,
                job.upload_path, DumpJson(job.params), now, now, job.attempts, job.kind)
      .Run();
}

Status Store::StartAttempt(const std::string& id) {
  std::lock_guard lock(write_mutex_);
  Statement s(writer_, "UPDATE jobs SET state='running', stage='survey', percent=0, attempts=attempts+1, updated=? WHERE id=?");
  return s.Bind(Now(), id).Run();
}

Status Store::ReturnAttempt(const std::string& id) {
  std::lock_guard lock(write_mutex_);
  Statement s(writer_, "UPDATE jobs SET attempts=MAX(attempts-1, 0), updated=? WHERE id=? AND state='running'");
  return s.Bind(Now(), id).Run();
}

Status Store::UpdateJobProgress(const std::string& id, const std::string& stage, double percent, uint64_t points_in,
                                uint64_t voxels_out) {
  std::lock_guard lock(write_mutex_);
  // Progress is best effort: it never waits for another process's lock, so it cannot slow the job.
  sqlite3_busy_timeout(writer_, 0);
  Statement s(writer_, "UPDATE jobs SET state='running', stage=?, percent=?, points_in=?, voxels_out=?, updated=? WHERE id=?");
  const Status status = s.Bind(stage, percent, points_in, voxels_out, Now(), id).Run();
  sqlite3_busy_timeout(writer_, busy_timeout_ms_);
  return status;
}

Status Store::SetJobState(const std::string& id, const std::string& state, const std::string& error) {
  std::lock_guard lock(write_mutex_);
  Statement s(writer_, "UPDATE jobs SET state=?, error=?, updated=? WHERE id=?");
  return s.Bind(state, error, Now(), id).Run();
}

StatusOr<std::optional<JobRecord>> Store::GetJob(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, (std::string(kJobColumns) + " WHERE id=?").c_str());
  s.Bind(id);
  ASSIGN_OR_RETURN(const bool found, s.Next());
  return found ? std::optional<JobRecord>(ReadJob(s)) : std::optional<JobRecord>();
}

StatusOr<std::vector<JobRecord>> Store::JobsInStates(const std::vector<std::string>& states) {
  std::lock_guard lock(read_mutex_);
  std::vector<JobRecord> out;
  for (const std::string& state : states) {
    Statement s(reader_, (std::string(kJobColumns) + " WHERE state=? ORDER BY created").c_str());
    s.Bind(state);
    for (;;) {
      ASSIGN_OR_RETURN(const bool row, s.Next());
      if (!row) break;
      out.push_back(ReadJob(s));
    }
  }
  return out;
}

StatusOr<std::map<std::string, uint64_t>> Store::JobCountsByState() {
  std::lock_guard lock(read_mutex_);
  std::map<std::string, uint64_t> out{{"queued", 0}, {"running", 0}, {"done", 0}, {"failed", 0}};
  Statement s(reader_, "SELECT state, COUNT(*) FROM jobs GROUP BY state");
  for (;;) {
    ASSIGN_OR_RETURN(const bool row, s.Next());
    if (!row) break;
    out[s.Text(0)] = static_cast<uint64_t>(s.Int(1));
  }
  return out;
}

Status Store::CommitDataset(const std::string& job_id, const std::string& dataset_id, const std::string& name,
                            const nlohmann::json& meta, const TileSet& tiles) {
  std::lock_guard lock(write_mutex_);
  RETURN_IF_ERROR(Exec(writer_, "BEGIN IMMEDIATE"));
  const auto body = [&]() -> Status {
    const double now = Now();
    RETURN_IF_ERROR(Statement(writer_, "INSERT INTO datasets VALUES (?,?,?,?)").Bind(dataset_id, name, now, DumpJson(meta)).Run());
    Statement insert(writer_, "INSERT INTO tiles VALUES (?,?,?,?,?,?,?,?)");
    for (const Tile& t : tiles.tiles) {
      insert.Reset();
      RETURN_IF_ERROR(insert.Bind(dataset_id, t.key.level, t.key.x, t.key.y, t.key.z, t.voxels, TileEtag(t.bytes), t.bytes).Run());
    }
    RETURN_IF_ERROR(Statement(writer_, "UPDATE jobs SET state='done', stage='done', percent=100, dataset_id=?, updated=? WHERE id=?")
                        .Bind(dataset_id, now, job_id)
                        .Run());
    return Exec(writer_, "COMMIT");
  };
  const Status status = body();
  if (!status.ok() && !sqlite3_get_autocommit(writer_)) (void)Exec(writer_, "ROLLBACK");
  return status;
}

StatusOr<std::optional<nlohmann::json>> Store::GetDataset(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, (std::string(kDatasetColumns) + " WHERE d.id=?").c_str());
  s.Bind(id);
  ASSIGN_OR_RETURN(const bool found, s.Next());
  if (!found) return std::optional<nlohmann::json>();
  ASSIGN_OR_RETURN(nlohmann::json meta, ReadDataset(s));
  return std::optional<nlohmann::json>(std::move(meta));
}

StatusOr<std::vector<nlohmann::json>> Store::ListDatasets() {
  std::lock_guard lock(read_mutex_);
  std::vector<nlohmann::json> out;
  Statement s(reader_, (std::string(kDatasetColumns) + " ORDER BY d.created").c_str());
  for (;;) {
    ASSIGN_OR_RETURN(const bool row, s.Next());
    if (!row) break;
    ASSIGN_OR_RETURN(nlohmann::json meta, ReadDataset(s));
    out.push_back(std::move(meta));
  }
  return out;
}

StatusOr<bool> Store::DeleteDataset(const std::string& id) {
  std::lock_guard lock(write_mutex_);
  RETURN_IF_ERROR(Exec(writer_, "BEGIN IMMEDIATE"));
  bool deleted = false;
  const auto body = [&]() -> Status {
    RETURN_IF_ERROR(Statement(writer_, "DELETE FROM datasets WHERE id=?").Bind(id).Run());
    deleted = sqlite3_changes(writer_) > 0;
    // The job keeps its dataset's id as history; its stage says the dataset is gone on purpose.
    RETURN_IF_ERROR(Statement(writer_, "UPDATE jobs SET stage='deleted', updated=? WHERE dataset_id=?").Bind(Now(), id).Run());
    return Exec(writer_, "COMMIT");
  };
  const Status status = body();
  if (!status.ok()) {
    if (!sqlite3_get_autocommit(writer_)) (void)Exec(writer_, "ROLLBACK");
    return status;
  }
  return deleted;
}

StatusOr<std::optional<StoredTile>> Store::GetTile(const std::string& dataset_id, const TileKey& key) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, "SELECT etag, bytes FROM tiles WHERE dataset_id=? AND level=? AND x=? AND y=? AND z=?");
  s.Bind(dataset_id, key.level, key.x, key.y, key.z);
  ASSIGN_OR_RETURN(const bool found, s.Next());
  return found ? std::optional<StoredTile>(StoredTile{s.Text(0), s.Blob(1)}) : std::optional<StoredTile>();
}

StatusOr<std::vector<HierarchyEntry>> Store::TilesBelow(const std::string& dataset_id, const TileKey& key, int depth,
                                                        std::vector<TileKey>& more_below) {
  std::lock_guard lock(read_mutex_);
  std::vector<HierarchyEntry> out;
  more_below.clear();
  // Descendants at level l of (L, X, Y, Z) are those with x >> (l - L) == X (and y, z alike).
  Statement s(reader_,
              "SELECT level, x, y, z, voxels, EXISTS (SELECT 1 FROM tiles c WHERE c.dataset_id = t.dataset_id AND "
              "c.level = t.level + 1 AND c.x >> 1 = t.x AND c.y >> 1 = t.y AND c.z >> 1 = t.z) "
              "FROM tiles t WHERE dataset_id=? AND level BETWEEN ? AND ? AND (x >> (level - ?)) = ? AND "
              "(y >> (level - ?)) = ? AND (z >> (level - ?)) = ? ORDER BY level, x, y, z");
  s.Bind(dataset_id, key.level, key.level + depth, key.level, key.x, key.level, key.y, key.level, key.z);
  for (;;) {
    ASSIGN_OR_RETURN(const bool row, s.Next());
    if (!row) break;
    const TileKey k{static_cast<int>(s.Int(0)), static_cast<uint32_t>(s.Int(1)), static_cast<uint32_t>(s.Int(2)),
                    static_cast<uint32_t>(s.Int(3))};
    out.push_back({k, static_cast<uint64_t>(s.Int(4))});
    if (k.level == key.level + depth && s.Int(5)) more_below.push_back(k);
  }
  return out;
}

}  // namespace pointdag::server
