// A test's own SQLite access to a daemon's store file, as another process would have it: to
// damage rows, hold the write lock, or read what is durable.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace pointdag::testing {

// Runs SQL on the store; false when SQLite refuses.
inline bool ExecSql(const std::filesystem::path& store, const std::string& sql) {
  sqlite3* db = nullptr;
  const bool ok = sqlite3_open_v2(store.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK &&
                  sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr) == SQLITE_OK;
  sqlite3_close(db);
  return ok;
}

// The first column of the first row as text ("" when none or on error).
inline std::string QueryText(sqlite3* db, const std::string& sql) {
  sqlite3_stmt* s = nullptr;
  std::string out;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) == SQLITE_OK && sqlite3_step(s) == SQLITE_ROW) {
    const auto* text = sqlite3_column_text(s, 0);
    if (text) out = reinterpret_cast<const char*>(text);
  }
  sqlite3_finalize(s);
  return out;
}

inline std::string QueryText(const std::filesystem::path& store, const std::string& sql) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(store.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  std::string out = QueryText(db, sql);
  sqlite3_close(db);
  return out;
}

// Another process holding the store's write lock (BEGIN EXCLUSIVE) until Release() or the end.
class StoreLock {
 public:
  explicit StoreLock(const std::filesystem::path& store) {
    sqlite3_open_v2(store.c_str(), &db_, SQLITE_OPEN_READWRITE, nullptr);
    held_ = sqlite3_exec(db_, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr) == SQLITE_OK;
  }
  ~StoreLock() { Release(); }
  bool held() const { return held_; }
  sqlite3* db() const { return db_; }  // reads what is committed, in the lock's transaction
  void Release() {
    if (db_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    sqlite3_close(db_);
    db_ = nullptr;
    held_ = false;
  }

 private:
  sqlite3* db_ = nullptr;
  bool held_ = false;
};

// Flips one byte of a stored tile's bytes, leaving its checksum (the ETag) as it was.
inline bool DamageTile(const std::filesystem::path& store, const std::string& dataset_id, size_t at) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(store.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr);
  const std::string where = " FROM tiles WHERE dataset_id = '" + dataset_id + "' AND level = 0";
  sqlite3_stmt* s = nullptr;
  std::vector<uint8_t> bytes;
  if (sqlite3_prepare_v2(db, ("SELECT bytes" + where).c_str(), -1, &s, nullptr) == SQLITE_OK && sqlite3_step(s) == SQLITE_ROW) {
    const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(s, 0));
    bytes.assign(p, p + sqlite3_column_bytes(s, 0));
  }
  sqlite3_finalize(s);
  bool ok = at < bytes.size();
  if (ok) {
    bytes[at] ^= 0xff;
    ok = sqlite3_prepare_v2(db, ("UPDATE tiles SET bytes = ? WHERE dataset_id = '" + dataset_id + "' AND level = 0").c_str(), -1,
                            &s, nullptr) == SQLITE_OK &&
         sqlite3_bind_blob(s, 1, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT) == SQLITE_OK &&
         sqlite3_step(s) == SQLITE_DONE;
    sqlite3_finalize(s);
  }
  sqlite3_close(db);
  return ok;
}

}  // namespace pointdag::testing
