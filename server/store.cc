#include "store.h"

#include "pointdag/json_text.h"

#include <xxhash.h>

#include <chrono>
#include <cstdio>
#include <random>

namespace pointdag::server {
namespace {

double Now() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }

// A prepared statement, finalized at scope end; Bind() takes values in placeholder order.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) stmt_ = nullptr;
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  bool ok() const { return stmt_ != nullptr; }

  template <typename... Args>
  Statement& Bind(const Args&... args) {
    int index = 0;
    (BindOne(++index, args), ...);
    return *this;
  }
  void Reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }
  // SQLITE_ROW, SQLITE_DONE or an error code.
  int Step() { return stmt_ ? sqlite3_step(stmt_) : SQLITE_MISUSE; }
  Status Run() {
    const int rc = Step();
    return rc == SQLITE_DONE || rc == SQLITE_ROW ? Status::Ok() : IoError(std::string("sqlite: ") + sqlite3_errmsg(db_));
  }
  std::string Text(int col) const {
    const auto* p = sqlite3_column_text(stmt_, col);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  int64_t Int(int col) const { return sqlite3_column_int64(stmt_, col); }
  double Real(int col) const { return sqlite3_column_double(stmt_, col); }
  std::vector<uint8_t> Blob(int col) const {
    const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, col));
    return p ? std::vector<uint8_t>(p, p + sqlite3_column_bytes(stmt_, col)) : std::vector<uint8_t>{};
  }

 private:
  void BindOne(int i, const std::string& v) { sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT); }
  void BindOne(int i, const char* v) { sqlite3_bind_text(stmt_, i, v, -1, SQLITE_TRANSIENT); }
  void BindOne(int i, double v) { sqlite3_bind_double(stmt_, i, v); }
  void BindOne(int i, int v) { sqlite3_bind_int64(stmt_, i, v); }
  void BindOne(int i, uint32_t v) { sqlite3_bind_int64(stmt_, i, v); }
  void BindOne(int i, uint64_t v) { sqlite3_bind_int64(stmt_, i, static_cast<int64_t>(v)); }
  void BindOne(int i, const std::vector<uint8_t>& v) { sqlite3_bind_blob(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_STATIC); }
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

Status Exec(sqlite3* db, const char* sql) {
  char* error = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &error) != SQLITE_OK) {
    std::string message = error ? error : "unknown";
    sqlite3_free(error);
    return IoError("sqlite: " + message);
  }
  return Status::Ok();
}

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  id TEXT PRIMARY KEY, state TEXT NOT NULL, stage TEXT NOT NULL, percent REAL NOT NULL,
  points_in INTEGER NOT NULL, voxels_out INTEGER NOT NULL, dataset_id TEXT NOT NULL, error TEXT NOT NULL,
  upload_path TEXT NOT NULL, params TEXT NOT NULL, created REAL NOT NULL, updated REAL NOT NULL);
CREATE TABLE IF NOT EXISTS datasets (
  id TEXT PRIMARY KEY, name TEXT NOT NULL, created REAL NOT NULL, meta TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS tiles (
  dataset_id TEXT NOT NULL REFERENCES datasets(id) ON DELETE CASCADE,
  level INTEGER NOT NULL, x INTEGER NOT NULL, y INTEGER NOT NULL, z INTEGER NOT NULL,
  voxels INTEGER NOT NULL, etag TEXT NOT NULL, bytes BLOB NOT NULL,
  PRIMARY KEY (dataset_id, level, x, y, z));
)sql";

StatusOr<sqlite3*> OpenConnection(const std::filesystem::path& file) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK) {
    std::string message = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    return IoError("cannot open the store " + file.string() + ": " + message);
  }
  sqlite3_busy_timeout(db, 10000);
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
  j.params = nlohmann::json::parse(s.Text(9), nullptr, false);
  j.created = s.Real(10);
  j.updated = s.Real(11);
  return j;
}

constexpr const char* kJobColumns =
    "SELECT id, state, stage, percent, points_in, voxels_out, dataset_id, error, upload_path, params, created, updated FROM jobs";

std::string TileEtag(const std::vector<uint8_t>& bytes) {
  char hex[40];
  std::snprintf(hex, sizeof(hex), "\"%016llx\"", static_cast<unsigned long long>(XXH3_64bits(bytes.data(), bytes.size())));
  return hex;
}

}  // namespace

std::string NewId() {
  static thread_local std::mt19937_64 rng(std::random_device{}());
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(rng()));
  return hex;
}

StatusOr<std::unique_ptr<Store>> Store::Open(const std::filesystem::path& file) {
  std::unique_ptr<Store> store(new Store());
  ASSIGN_OR_RETURN(store->writer_, OpenConnection(file));
  RETURN_IF_ERROR(Exec(store->writer_, "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON;"));
  RETURN_IF_ERROR(Exec(store->writer_, kSchema));
  ASSIGN_OR_RETURN(store->reader_, OpenConnection(file));
  return store;
}

Store::~Store() {
  sqlite3_close(reader_);
  sqlite3_close(writer_);
}

Status Store::CreateJob(const JobRecord& job) {
  std::lock_guard lock(write_mutex_);
  Statement s(writer_, "INSERT INTO jobs VALUES (?,?,?,?,?,?,?,?,?,?,?,?)");
  const double now = Now();
  return s.Bind(job.id, job.state, job.stage, job.percent, job.points_in, job.voxels_out, job.dataset_id, job.error,
                job.upload_path, DumpJson(job.params), now, now)
      .Run();
}

Status Store::UpdateJobProgress(const std::string& id, const std::string& stage, double percent, uint64_t points_in,
                                uint64_t voxels_out) {
  std::lock_guard lock(write_mutex_);
  Statement s(writer_, "UPDATE jobs SET state='running', stage=?, percent=?, points_in=?, voxels_out=?, updated=? WHERE id=?");
  return s.Bind(stage, percent, points_in, voxels_out, Now(), id).Run();
}

Status Store::SetJobState(const std::string& id, const std::string& state, const std::string& error) {
  std::lock_guard lock(write_mutex_);
  Statement s(writer_, "UPDATE jobs SET state=?, error=?, updated=? WHERE id=?");
  return s.Bind(state, error, Now(), id).Run();
}

std::optional<JobRecord> Store::GetJob(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, (std::string(kJobColumns) + " WHERE id=?").c_str());
  s.Bind(id);
  if (s.Step() != SQLITE_ROW) return std::nullopt;
  return ReadJob(s);
}

std::vector<JobRecord> Store::JobsInStates(const std::vector<std::string>& states) {
  std::lock_guard lock(read_mutex_);
  std::vector<JobRecord> out;
  for (const std::string& state : states) {
    Statement s(reader_, (std::string(kJobColumns) + " WHERE state=? ORDER BY created").c_str());
    s.Bind(state);
    while (s.Step() == SQLITE_ROW) out.push_back(ReadJob(s));
  }
  return out;
}

std::map<std::string, uint64_t> Store::JobCountsByState() {
  std::lock_guard lock(read_mutex_);
  std::map<std::string, uint64_t> out{{"queued", 0}, {"running", 0}, {"done", 0}, {"failed", 0}};
  Statement s(reader_, "SELECT state, COUNT(*) FROM jobs GROUP BY state");
  while (s.Step() == SQLITE_ROW) out[s.Text(0)] = static_cast<uint64_t>(s.Int(1));
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
    return Statement(writer_, "UPDATE jobs SET state='done', stage='done', percent=100, dataset_id=?, updated=? WHERE id=?")
        .Bind(dataset_id, now, job_id)
        .Run();
  };
  const Status status = body();
  if (!status.ok()) {
    (void)Exec(writer_, "ROLLBACK");
    return status;
  }
  return Exec(writer_, "COMMIT");
}

std::optional<nlohmann::json> Store::GetDataset(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, "SELECT meta FROM datasets WHERE id=?");
  s.Bind(id);
  if (s.Step() != SQLITE_ROW) return std::nullopt;
  return nlohmann::json::parse(s.Text(0));
}

std::vector<nlohmann::json> Store::ListDatasets() {
  std::lock_guard lock(read_mutex_);
  std::vector<nlohmann::json> out;
  Statement s(reader_, "SELECT meta FROM datasets ORDER BY created");
  while (s.Step() == SQLITE_ROW) out.push_back(nlohmann::json::parse(s.Text(0)));
  return out;
}

bool Store::DeleteDataset(const std::string& id) {
  std::lock_guard lock(write_mutex_);
  if (!Statement(writer_, "DELETE FROM datasets WHERE id=?").Bind(id).Run().ok()) return false;
  return sqlite3_changes(writer_) > 0;
}

std::optional<StoredTile> Store::GetTile(const std::string& dataset_id, const TileKey& key) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, "SELECT etag, bytes FROM tiles WHERE dataset_id=? AND level=? AND x=? AND y=? AND z=?");
  s.Bind(dataset_id, key.level, key.x, key.y, key.z);
  if (s.Step() != SQLITE_ROW) return std::nullopt;
  return StoredTile{s.Text(0), s.Blob(1)};
}

std::vector<HierarchyEntry> Store::TilesBelow(const std::string& dataset_id, const TileKey& key, int depth,
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
  while (s.Step() == SQLITE_ROW) {
    const TileKey k{static_cast<int>(s.Int(0)), static_cast<uint32_t>(s.Int(1)), static_cast<uint32_t>(s.Int(2)),
                    static_cast<uint32_t>(s.Int(3))};
    out.push_back({k, static_cast<uint64_t>(s.Int(4))});
    if (k.level == key.level + depth && s.Int(5)) more_below.push_back(k);
  }
  return out;
}

}  // namespace pointdag::server
