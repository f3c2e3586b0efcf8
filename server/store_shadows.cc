// The store's shadow sets (store.h): a dataset's summary row and one layer per tile, replaced whole.
#include <chrono>

#include "pointdag/json_text.h"
#include "sqlite_util.h"
#include "store.h"

namespace pointdag::server {
namespace {

double Now() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }

// Runs `body` inside BEGIN IMMEDIATE ... COMMIT on `db`, rolled back when it fails.
template <typename Body>
Status InTransaction(sqlite3* db, Body&& body) {
  RETURN_IF_ERROR(Exec(db, "BEGIN IMMEDIATE"));
  Status status = body();
  if (status.ok()) status = Exec(db, "COMMIT");
  if (!status.ok() && !sqlite3_get_autocommit(db)) (void)Exec(db, "ROLLBACK");
  return status;
}

}  // namespace

StatusOr<std::optional<std::string>> Store::CreateShadowJob(const JobRecord& job) {
  std::optional<std::string> existing;
  std::lock_guard lock(write_mutex_);
  const auto body = [&]() -> Status {
    Statement busy(writer_,
                   "SELECT id FROM jobs WHERE kind='shadows' AND dataset_id=? AND state IN ('queued','running') "
                   "ORDER BY created LIMIT 1");
    ASSIGN_OR_RETURN(const bool found, busy.Bind(job.dataset_id).Next());
    if (found) {
      existing = busy.Text(0);
      return Status::Ok();
    }
    const double now = Now();
    return Statement(writer_,
                     "INSERT INTO jobs (id, state, stage, percent, points_in, voxels_out, dataset_id, error, upload_path, "
                     "params, created, updated, attempts, kind) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)")
        .Bind(job.id, job.state, job.stage, job.percent, job.points_in, job.voxels_out, job.dataset_id, job.error,
              job.upload_path, DumpJson(job.params), now, now, job.attempts, std::string("shadows"))
        .Run();
  };
  RETURN_IF_ERROR(InTransaction(writer_, body));
  return existing;
}

Status Store::CommitShadows(const std::string& job_id, const std::string& dataset_id, const nlohmann::json& summary,
                            const std::vector<ShadowTile>& layers, const std::vector<uint8_t>& shadow_dag) {
  std::lock_guard lock(write_mutex_);
  return InTransaction(writer_, [&]() -> Status {
    Statement dataset(writer_, "SELECT 1 FROM datasets WHERE id=?");
    ASSIGN_OR_RETURN(const bool exists, dataset.Bind(dataset_id).Next());
    if (!exists) return InvalidArgument("dataset " + dataset_id + " was deleted while its shadows were computed");
    const double now = Now();
    // The old set's layers go with it (ON DELETE CASCADE).
    RETURN_IF_ERROR(Statement(writer_, "DELETE FROM shadow_sets WHERE dataset_id=?").Bind(dataset_id).Run());
    RETURN_IF_ERROR(Statement(writer_, "INSERT INTO shadow_sets VALUES (?,?,?,?)")
                        .Bind(dataset_id, job_id, now, DumpJson(summary))
                        .Run());
    Statement insert(writer_, "INSERT INTO shadow_tiles VALUES (?,?,?,?,?,?,?,?)");
    for (const ShadowTile& t : layers) {
      insert.Reset();
      RETURN_IF_ERROR(insert.Bind(dataset_id, t.key.level, t.key.x, t.key.y, t.key.z, t.voxels, TileEtag(t.bytes), t.bytes).Run());
    }
    if (!shadow_dag.empty()) {
      RETURN_IF_ERROR(Statement(writer_, "INSERT INTO shadow_dags VALUES (?,?,?)")
                          .Bind(dataset_id, TileEtag(shadow_dag), shadow_dag)
                          .Run());
    }
    return Statement(writer_, "UPDATE jobs SET state='done', stage='done', percent=100, updated=? WHERE id=?")
        .Bind(now, job_id)
        .Run();
  });
}

StatusOr<std::optional<nlohmann::json>> Store::GetShadows(const std::string& dataset_id) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, "SELECT summary FROM shadow_sets WHERE dataset_id=?");
  ASSIGN_OR_RETURN(const bool found, s.Bind(dataset_id).Next());
  if (!found) return std::optional<nlohmann::json>();
  auto summary = ParseJson(s.Text(0));
  if (!summary.ok()) return Corrupt("the shadow summary of dataset " + dataset_id + " is not JSON: " + summary.status().message());
  return std::optional<nlohmann::json>(std::move(*summary));
}

StatusOr<std::optional<StoredTile>> Store::GetShadowTile(const std::string& dataset_id, const TileKey& key) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, "SELECT etag, bytes FROM shadow_tiles WHERE dataset_id=? AND level=? AND x=? AND y=? AND z=?");
  ASSIGN_OR_RETURN(const bool found, s.Bind(dataset_id, key.level, key.x, key.y, key.z).Next());
  return found ? std::optional<StoredTile>(StoredTile{s.Text(0), s.Blob(1)}) : std::optional<StoredTile>();
}

StatusOr<std::optional<StoredTile>> Store::GetShadowDag(const std::string& dataset_id) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, "SELECT etag, bytes FROM shadow_dags WHERE dataset_id=?");
  ASSIGN_OR_RETURN(const bool found, s.Bind(dataset_id).Next());
  return found ? std::optional<StoredTile>(StoredTile{s.Text(0), s.Blob(1)}) : std::optional<StoredTile>();
}

StatusOr<std::optional<std::string>> Store::GetShadowDagEtag(const std::string& dataset_id) {
  std::lock_guard lock(read_mutex_);
  Statement s(reader_, "SELECT etag FROM shadow_dags WHERE dataset_id=?");
  ASSIGN_OR_RETURN(const bool found, s.Bind(dataset_id).Next());
  return found ? std::optional<std::string>(s.Text(0)) : std::optional<std::string>();
}

StatusOr<bool> Store::DeleteShadows(const std::string& dataset_id) {
  std::lock_guard lock(write_mutex_);
  bool deleted = false;
  const auto body = [&]() -> Status {
    RETURN_IF_ERROR(Statement(writer_, "DELETE FROM shadow_sets WHERE dataset_id=?").Bind(dataset_id).Run());
    deleted = sqlite3_changes(writer_) > 0;
    return Status::Ok();
  };
  RETURN_IF_ERROR(InTransaction(writer_, body));
  return deleted;
}

}  // namespace pointdag::server
