// The SQL the store's files share (result_store.cpp, store_maintenance.cpp):
// the schema, and small helpers over the sqlite3 C API.
#pragma once

#include <sqlite3.h>

#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shimmer/experiments/result_store.h"

namespace shimmer::experiments::store_sql {


// Columns every report needs are real columns; the full metrics JSON is kept too.
inline constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  id TEXT PRIMARY KEY,
  reference_id TEXT NOT NULL,
  scene TEXT NOT NULL, material TEXT NOT NULL, camera TEXT NOT NULL,
  variant TEXT NOT NULL, params TEXT NOT NULL, derivatives TEXT NOT NULL,
  width INTEGER, height INTEGER, frames INTEGER, fps REAL,
  reference_spp INTEGER, reference_tolerance REAL,
  tv_ratio REAL, tv_err REAL, energy_bias REAL, temporal_diff_err REAL, relmse REAL, flicker_index REAL,
  metrics TEXT NOT NULL,
  job TEXT NOT NULL,
  gpu_ms_per_frame REAL, wall_s REAL,
  revision TEXT, core_version TEXT,
  finished_at TEXT DEFAULT (datetime('now')),
  device TEXT, driver TEXT,
  sources TEXT,
  draws BLOB
);
CREATE TABLE IF NOT EXISTS shots (
  reference_id TEXT PRIMARY KEY,
  scene TEXT NOT NULL, material TEXT NOT NULL, camera TEXT NOT NULL,
  converged INTEGER NOT NULL,
  check_json TEXT NOT NULL,
  finished_at TEXT DEFAULT (datetime('now'))
);
CREATE TABLE IF NOT EXISTS benchmarks (
  scene TEXT NOT NULL, derivatives TEXT NOT NULL, variant TEXT NOT NULL, params TEXT NOT NULL,
  width INTEGER NOT NULL, height INTEGER NOT NULL, device TEXT NOT NULL,
  median_ms REAL, ratio_to_none REAL,
  cost_json TEXT NOT NULL,
  finished_at TEXT DEFAULT (datetime('now')),
  PRIMARY KEY (scene, derivatives, variant, params, width, height, device)
);
CREATE TABLE IF NOT EXISTS fits (
  variant TEXT NOT NULL, param TEXT NOT NULL, material TEXT NOT NULL,
  value REAL, j_train REAL, j_validate REAL,
  result TEXT NOT NULL,
  finished_at TEXT DEFAULT (datetime('now')),
  map TEXT NOT NULL DEFAULT '',
  PRIMARY KEY (variant, param, material, map)
);
)sql";

// Stores from before fits per normal map keyed a fit by (variant, param,
// material); SQLite cannot change a primary key in place, so the rows move to
// a new table in one transaction.
inline constexpr const char* kFitsByMap = R"sql(
BEGIN;
CREATE TABLE fits_by_map (
  variant TEXT NOT NULL, param TEXT NOT NULL, material TEXT NOT NULL,
  value REAL, j_train REAL, j_validate REAL,
  result TEXT NOT NULL,
  finished_at TEXT DEFAULT (datetime('now')),
  map TEXT NOT NULL DEFAULT '',
  PRIMARY KEY (variant, param, material, map)
);
INSERT INTO fits_by_map (variant, param, material, value, j_train, j_validate, result, finished_at)
  SELECT variant, param, material, value, j_train, j_validate, result, finished_at FROM fits;
DROP TABLE fits;
ALTER TABLE fits_by_map RENAME TO fits;
COMMIT;
)sql";

struct Statement {
  sqlite3_stmt* stmt = nullptr;
  ~Statement() { sqlite3_finalize(stmt); }
};

// The JSON column of every row `sql` selects, parsed; a store from before the
// table existed has none. Nullopt: a row does not parse.
inline std::optional<std::vector<nlohmann::json>> JsonRows(sqlite3* db, const char* sql) {
  std::vector<nlohmann::json> out;
  Statement s;
  if (sqlite3_prepare_v2(db, sql, -1, &s.stmt, nullptr) != SQLITE_OK) return out;
  while (sqlite3_step(s.stmt) == SQLITE_ROW) {
    const unsigned char* text = sqlite3_column_text(s.stmt, 0);
    auto j = nlohmann::json::parse(text ? reinterpret_cast<const char*>(text) : "", nullptr, false);
    if (j.is_discarded() || !j.is_object()) return std::nullopt;
    out.push_back(std::move(j));
  }
  return out;
}

// Rows of `sql` read back as T (the table's JSON column); `what` names a
// damaged row in the message.
template <typename T>
inline Result<std::vector<T>> TypedRows(sqlite3* db, const char* sql, const std::string& path, const std::string& what) {
  auto rows = JsonRows(db, sql);
  if (!rows) return Result<std::vector<T>>::Failure(path + ": a " + what + " row is damaged");
  std::vector<T> out;
  try {
    for (const nlohmann::json& j : *rows) out.push_back(j.get<T>());
  } catch (const nlohmann::json::exception&) {
    return Result<std::vector<T>>::Failure(path + ": a " + what + " row is damaged");
  }
  return out;
}

// Columns of `jobs` in the order Insert writes them; a store from before a
// column existed reads NULL for it.
inline constexpr const char* kJobColumns[] = {"id",
                             "reference_id",
                             "scene",
                             "material",
                             "camera",
                             "variant",
                             "params",
                             "derivatives",
                             "width",
                             "height",
                             "frames",
                             "fps",
                             "reference_spp",
                             "reference_tolerance",
                             "tv_ratio",
                             "tv_err",
                             "energy_bias",
                             "temporal_diff_err",
                             "relmse",
                             "flicker_index",
                             "metrics",
                             "job",
                             "gpu_ms_per_frame",
                             "wall_s",
                             "revision",
                             "core_version",
                             "finished_at",
                             "device",
                             "driver",
                             "sources",
                             "draws"};

inline std::string SqlQuote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

inline std::set<std::string> ColumnsOf(sqlite3* db, const std::string& schema, const std::string& table = "jobs") {
  std::set<std::string> columns;
  Statement s;
  if (sqlite3_prepare_v2(db, ("PRAGMA " + schema + ".table_info(" + table + ")").c_str(), -1, &s.stmt, nullptr) !=
      SQLITE_OK)
    return columns;
  while (sqlite3_step(s.stmt) == SQLITE_ROW)
    columns.insert(reinterpret_cast<const char*>(sqlite3_column_text(s.stmt, 1)));
  return columns;
}

inline bool HasTable(sqlite3* db, const char* schema, const char* name) {
  Statement s;
  const std::string sql = std::string("SELECT 1 FROM ") + schema + ".sqlite_master WHERE type = 'table' AND name = ?";
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s.stmt, nullptr) != SQLITE_OK) return false;
  sqlite3_bind_text(s.stmt, 1, name, -1, SQLITE_STATIC);
  return sqlite3_step(s.stmt) == SQLITE_ROW;
}

// A store's path as an SQLite URI with `query` ("mode=ro", "immutable=1"):
// the characters URIs reserve are percent-encoded, so any file name works.
inline std::string StoreUri(const std::string& path, const char* query) {
  std::string uri = "file:";
  for (char c : path) {
    if (c == '%' || c == '?' || c == '#') {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", static_cast<unsigned char>(c));
      uri += buf;
    } else {
      uri += c;
    }
  }
  return uri + "?" + query;
}

inline bool IsIoError(sqlite3* db) {
  const int code = sqlite3_errcode(db);
  return code == SQLITE_IOERR || code == SQLITE_FULL || code == SQLITE_READONLY || code == SQLITE_CANTOPEN;
}

// SQLite's "disk I/O error" says nothing of the cause; the system's errno does ("File too large").
inline std::string WithSystemReason(sqlite3* db, std::string message) {
  if (IsIoError(db) && sqlite3_system_errno(db) != 0) message += ": " + SystemReason(sqlite3_system_errno(db));
  return message;
}

inline Status ExecOn(sqlite3* db, const std::string& sql) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
    std::string error = WithSystemReason(db, message ? message : "sqlite error");
    sqlite3_free(message);
    return Status::Failure(error, IsIoError(db) ? ErrorCode::kIo : ErrorCode::kBadInput);
  }
  return Ok();
}

}  // namespace shimmer::experiments::store_sql
