#include "check.h"

#include <map>
#include <set>

#include "pointdag/container/pdag_file.h"
#include "pointdag/json_text.h"
#include "pointdag/shadow/shadow_dag.h"
#include "pointdag/shadow/shadow_layer.h"
#include "sqlite_util.h"
#include "store.h"

namespace pointdag::server {
namespace {

// A read-only connection, closed at scope end.
struct Connection {
  sqlite3* db = nullptr;
  ~Connection() { sqlite3_close(db); }
};

// Runs one query; `row` sees each result row.
template <typename RowFn>
Status ForEachRow(sqlite3* db, const char* sql, RowFn row) {
  Statement s(db, sql);
  for (;;) {
    ASSIGN_OR_RETURN(const bool more, s.Next());
    if (!more) return Status::Ok();
    row(s);
  }
}

Status CheckDatasets(sqlite3* db, CheckReport& report) {
  std::map<std::string, int64_t> stored_counts;
  RETURN_IF_ERROR(ForEachRow(db, "SELECT dataset_id, COUNT(*) FROM tiles GROUP BY dataset_id",
                             [&](const Statement& s) { stored_counts[s.Text(0)] = s.Int(1); }));
  std::set<std::string> datasets;
  RETURN_IF_ERROR(ForEachRow(db, "SELECT id, meta FROM datasets", [&](const Statement& s) {
    const std::string id = s.Text(0);
    datasets.insert(id);
    ++report.datasets;
    const auto meta = ParseJson(s.Text(1));
    if (!meta.ok() || !meta->is_object() || !(*meta)["tile_count"].is_number_unsigned()) {
      report.problems.push_back("dataset " + id + ": its metadata is not JSON with a tile_count");
      return;
    }
    const auto declared = (*meta)["tile_count"].get<uint64_t>();
    const int64_t stored = stored_counts.count(id) ? stored_counts.at(id) : 0;
    if (static_cast<uint64_t>(stored) != declared) {
      report.problems.push_back("dataset " + id + ": " + std::to_string(stored) + " tiles stored, its metadata says " +
                                std::to_string(declared));
    }
  }));
  for (const auto& [id, count] : stored_counts) {
    if (!datasets.count(id)) report.problems.push_back(std::to_string(count) + " orphan tile(s) of no dataset (" + id + ")");
  }
  return Status::Ok();
}

Status CheckTiles(sqlite3* db, CheckReport& report) {
  return ForEachRow(db, "SELECT dataset_id, level, x, y, z, etag, bytes FROM tiles", [&](const Statement& s) {
    ++report.tiles;
    const std::string where = "tile " + std::to_string(s.Int(1)) + "/" + std::to_string(s.Int(2)) + "/" +
                              std::to_string(s.Int(3)) + "/" + std::to_string(s.Int(4)) + " of dataset " + s.Text(0);
    const std::vector<uint8_t> bytes = s.Blob(6);
    if (TileEtag(bytes) != s.Text(5)) {
      report.problems.push_back(where + ": its bytes do not match their checksum " + s.Text(5));
      return;
    }
    if (const auto parsed = ParsePdag(bytes); !parsed.ok()) {
      report.problems.push_back(where + ": not a valid .pdag: " + parsed.status().ToString());
    }
  });
}

// Every shadow set whole: one layer per tile of its dataset, each matching its checksum and
// decoding to its tile's voxel count. Stores from before shadows have no such tables.
Status CheckShadows(sqlite3* db, CheckReport& report) {
  bool present = false;
  RETURN_IF_ERROR(ForEachRow(db, "SELECT 1 FROM sqlite_master WHERE name = 'shadow_tiles'", [&](const Statement&) { present = true; }));
  if (!present) return Status::Ok();
  RETURN_IF_ERROR(ForEachRow(db,
                             "SELECT s.dataset_id, (SELECT COUNT(*) FROM tiles t WHERE t.dataset_id = s.dataset_id), "
                             "(SELECT COUNT(*) FROM shadow_tiles l WHERE l.dataset_id = s.dataset_id) FROM shadow_sets s",
                             [&](const Statement& s) {
                               if (s.Int(1) == s.Int(2)) return;
                               report.problems.push_back("the shadow set of dataset " + s.Text(0) + " has " +
                                                         std::to_string(s.Int(2)) + " layers for " + std::to_string(s.Int(1)) + " tiles");
                             }));
  return ForEachRow(db,
                    "SELECT l.dataset_id, l.level, l.x, l.y, l.z, l.etag, l.bytes, t.voxels FROM shadow_tiles l LEFT JOIN tiles t "
                    "ON t.dataset_id = l.dataset_id AND t.level = l.level AND t.x = l.x AND t.y = l.y AND t.z = l.z",
                    [&](const Statement& s) {
                      const std::string where = "shadow layer " + std::to_string(s.Int(1)) + "/" + std::to_string(s.Int(2)) + "/" +
                                                std::to_string(s.Int(3)) + "/" + std::to_string(s.Int(4)) + " of dataset " + s.Text(0);
                      const std::vector<uint8_t> bytes = s.Blob(6);
                      if (s.IsNull(7)) {
                        report.problems.push_back(where + ": no such tile");
                      } else if (TileEtag(bytes) != s.Text(5)) {
                        report.problems.push_back(where + ": its bytes do not match their checksum " + s.Text(5));
                      } else if (const auto layer = DecodeShadowLayer(bytes, static_cast<uint64_t>(s.Int(7))); !layer.ok()) {
                        report.problems.push_back(where + ": " + layer.status().ToString());
                      }
                    });
}

// Every stored shadow DAG matches its checksum and reads back (ShadowDag::Deserialize's checks).
// Stores from before shadow DAGs were kept have no such table.
Status CheckShadowDags(sqlite3* db, CheckReport& report) {
  bool present = false;
  RETURN_IF_ERROR(ForEachRow(db, "SELECT 1 FROM sqlite_master WHERE name = 'shadow_dags'", [&](const Statement&) { present = true; }));
  if (!present) return Status::Ok();
  return ForEachRow(db, "SELECT dataset_id, etag, bytes FROM shadow_dags", [&](const Statement& s) {
    const std::string where = "the shadow DAG of dataset " + s.Text(0);
    const std::vector<uint8_t> bytes = s.Blob(2);
    if (TileEtag(bytes) != s.Text(1)) {
      report.problems.push_back(where + ": its bytes do not match their checksum " + s.Text(1));
    } else if (const auto dag = ShadowDag::Deserialize(bytes); !dag.ok()) {
      report.problems.push_back(where + ": " + dag.status().ToString());
    }
  });
}

Status CheckJobs(sqlite3* db, const std::filesystem::path& upload_dir, CheckReport& report) {
  std::set<std::string> datasets;
  RETURN_IF_ERROR(ForEachRow(db, "SELECT id FROM datasets", [&](const Statement& s) { datasets.insert(s.Text(0)); }));
  std::set<std::filesystem::path> referenced;
  RETURN_IF_ERROR(ForEachRow(db, "SELECT id, state, stage, dataset_id, error, upload_path FROM jobs", [&](const Statement& s) {
    ++report.jobs;
    const std::string job = "job " + s.Text(0), state = s.Text(1);
    if (state == "queued" || state == "running") {
      referenced.insert(s.Text(5));
    } else if (state == "failed") {
      if (s.Text(4).empty()) report.problems.push_back(job + ": failed without a reason");
    } else if (state == "done") {
      if (s.Text(2) != "deleted" && !datasets.count(s.Text(3))) {
        report.problems.push_back(job + ": done, but its dataset " + s.Text(3) + " does not exist");
      }
    } else {
      report.problems.push_back(job + ": unknown state '" + state + "'");
    }
  }));
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(upload_dir, ec)) {
    ++report.uploads;
    if (!referenced.count(entry.path())) {
      report.problems.push_back("orphan upload " + entry.path().string() + ": no queued or running job references it");
    }
  }
  return Status::Ok();
}

}  // namespace

std::string CheckReport::ToString() const {
  std::string out = (ok() ? "consistent: " : "INCONSISTENT: ") + std::to_string(datasets) + " dataset(s), " +
                    std::to_string(tiles) + " tile(s), " + std::to_string(jobs) + " job(s), " + std::to_string(uploads) +
                    " upload(s)" + (ok() ? "" : ", " + std::to_string(problems.size()) + " problem(s):") + "\n";
  for (const std::string& p : problems) out += "  " + p + "\n";
  return out;
}

StatusOr<CheckReport> CheckDataDir(const std::filesystem::path& data_dir) {
  const auto file = data_dir / "store.sqlite";
  if (!std::filesystem::exists(file)) return IoError("no store at " + file.string());
  Connection c;
  if (const int rc = sqlite3_open_v2(file.c_str(), &c.db, SQLITE_OPEN_READONLY, nullptr); rc != SQLITE_OK) {
    return IoError("cannot open " + file.string() + ": " + (c.db ? sqlite3_errmsg(c.db) : "out of memory"));
  }
  sqlite3_busy_timeout(c.db, Store::kBusyTimeoutMs);
  CheckReport report;
  RETURN_IF_ERROR(ForEachRow(c.db, "PRAGMA quick_check", [&](const Statement& s) {
    if (s.Text(0) != "ok") report.problems.push_back("sqlite: " + s.Text(0));
  }));
  RETURN_IF_ERROR(CheckDatasets(c.db, report));
  RETURN_IF_ERROR(CheckTiles(c.db, report));
  RETURN_IF_ERROR(CheckShadows(c.db, report));
  RETURN_IF_ERROR(CheckShadowDags(c.db, report));
  RETURN_IF_ERROR(CheckJobs(c.db, data_dir / "uploads", report));
  return report;
}

}  // namespace pointdag::server
