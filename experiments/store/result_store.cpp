#include "result_store.h"

#include <sqlite3.h>

#include <cmath>
#include <filesystem>

namespace shimmer::experiments {

namespace {

// Columns every report needs are real columns; the full metrics JSON is kept too.
const char* kSchema = R"sql(
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
  finished_at TEXT DEFAULT (datetime('now'))
);
CREATE TABLE IF NOT EXISTS fits (
  variant TEXT NOT NULL, param TEXT NOT NULL, material TEXT NOT NULL,
  value REAL, j_train REAL, j_validate REAL,
  result TEXT NOT NULL,
  finished_at TEXT DEFAULT (datetime('now')),
  PRIMARY KEY (variant, param, material)
);
)sql";

struct Statement {
  sqlite3_stmt* stmt = nullptr;
  ~Statement() { sqlite3_finalize(stmt); }
};

}  // namespace

double Metric(const nlohmann::json& metrics, const char* key) {
  return metrics.contains(key) && metrics[key].is_number() ? metrics[key].get<double>() : std::nan("");
}

double FlickerIndex(const nlohmann::json& metrics) {
  return metrics.contains("flicker") ? Metric(metrics["flicker"], "flicker_index") : std::nan("");
}

ResultStore::ResultStore(sqlite3* db) : db_(db) {}
ResultStore::~ResultStore() { sqlite3_close(db_); }

std::pair<std::unique_ptr<ResultStore>, std::string> ResultStore::Open(const std::string& path) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
    std::string error = path + ": cannot open results store: " + (db ? sqlite3_errmsg(db) : "out of memory");
    sqlite3_close(db);
    return {nullptr, error};
  }
  std::unique_ptr<ResultStore> store(new ResultStore(db));
  sqlite3_busy_timeout(db, 10000);
  // WAL: a reader (report) never blocks the runner, and a crash mid-write rolls back cleanly.
  std::string error = store->Exec("PRAGMA journal_mode=WAL;");
  if (error.empty()) error = store->Exec(kSchema);
  if (!error.empty()) return {nullptr, path + ": " + error};
  return {std::move(store), ""};
}

std::string ResultStore::Exec(const std::string& sql) {
  char* message = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
    std::string error = message ? message : "sqlite error";
    sqlite3_free(message);
    return error;
  }
  return "";
}

bool ResultStore::Has(const std::string& id) {
  Statement s;
  sqlite3_prepare_v2(db_, "SELECT 1 FROM jobs WHERE id = ?", -1, &s.stmt, nullptr);
  sqlite3_bind_text(s.stmt, 1, id.c_str(), -1, SQLITE_TRANSIENT);
  return sqlite3_step(s.stmt) == SQLITE_ROW;
}

std::string ResultStore::Insert(const JobResult& r) {
  std::string error = Exec("BEGIN IMMEDIATE;");
  if (!error.empty()) return error;
  Statement s;
  sqlite3_prepare_v2(db_,
                     "INSERT OR REPLACE INTO jobs (id, reference_id, scene, material, camera, variant, params, "
                     "derivatives, width, height, frames, fps, reference_spp, reference_tolerance, tv_ratio, tv_err, "
                     "energy_bias, temporal_diff_err, relmse, flicker_index, metrics, job, gpu_ms_per_frame, wall_s, "
                     "revision, core_version) VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)",
                     -1, &s.stmt, nullptr);
  int i = 1;
  auto text = [&](const std::string& v) { sqlite3_bind_text(s.stmt, i++, v.c_str(), -1, SQLITE_TRANSIENT); };
  auto real = [&](double v) {
    if (std::isnan(v))
      sqlite3_bind_null(s.stmt, i++);
    else
      sqlite3_bind_double(s.stmt, i++, v);
  };
  text(r.id);
  text(r.reference_id);
  text(r.job.scene);
  text(r.job.material);
  text(r.job.camera);
  text(r.job.variant);
  text(nlohmann::json(r.job.params).dump());
  text(r.job.derivatives);
  sqlite3_bind_int(s.stmt, i++, r.job.width);
  sqlite3_bind_int(s.stmt, i++, r.job.height);
  sqlite3_bind_int(s.stmt, i++, r.job.frames);
  real(r.job.fps);
  sqlite3_bind_int(s.stmt, i++, r.job.reference.spp);
  real(r.job.reference.tolerance);
  for (const char* key : {"tv_ratio", "tv_err", "energy_bias", "temporal_diff_err", "relmse"}) real(Metric(r.metrics, key));
  real(FlickerIndex(r.metrics));
  text(r.metrics.dump());
  text(r.job.ToJson().dump());
  real(r.gpu_ms_per_frame);
  real(r.wall_s);
  text(r.revision);
  text(r.core_version);
  if (sqlite3_step(s.stmt) != SQLITE_DONE) {
    error = sqlite3_errmsg(db_);
    Exec("ROLLBACK;");
    return error;
  }
  return Exec("COMMIT;");
}

std::vector<JobResult> ResultStore::All() { return Select("", ""); }

std::optional<JobResult> ResultStore::Get(const std::string& id) {
  std::vector<JobResult> rows = Select("WHERE id = ?", id);
  if (rows.empty()) return std::nullopt;
  return std::move(rows.front());
}

std::vector<JobResult> ResultStore::Select(const std::string& where, const std::string& id) {
  std::vector<JobResult> rows;
  Statement s;
  const std::string sql =
      "SELECT id, reference_id, scene, material, camera, variant, params, derivatives, width, height, "
      "frames, fps, reference_spp, reference_tolerance, metrics, gpu_ms_per_frame, wall_s, revision, "
      "core_version, job FROM jobs " + where + " ORDER BY id";
  sqlite3_prepare_v2(db_, sql.c_str(), -1, &s.stmt, nullptr);
  if (!id.empty()) sqlite3_bind_text(s.stmt, 1, id.c_str(), -1, SQLITE_TRANSIENT);
  auto str = [&](int c) {
    const unsigned char* t = sqlite3_column_text(s.stmt, c);
    return t ? std::string(reinterpret_cast<const char*>(t)) : std::string();
  };
  while (sqlite3_step(s.stmt) == SQLITE_ROW) {
    JobResult r;
    r.id = str(0);
    r.reference_id = str(1);
    r.job.scene = str(2);
    r.job.material = str(3);
    r.job.camera = str(4);
    r.job.variant = str(5);
    r.job.params = nlohmann::json::parse(str(6)).get<std::map<std::string, double>>();
    r.job.derivatives = str(7);
    r.job.width = sqlite3_column_int(s.stmt, 8);
    r.job.height = sqlite3_column_int(s.stmt, 9);
    r.job.frames = sqlite3_column_int(s.stmt, 10);
    r.job.fps = sqlite3_column_double(s.stmt, 11);
    r.job.reference.spp = sqlite3_column_int(s.stmt, 12);
    r.job.reference.tolerance = sqlite3_column_double(s.stmt, 13);
    r.metrics = nlohmann::json::parse(str(14));
    r.gpu_ms_per_frame = sqlite3_column_double(s.stmt, 15);
    r.wall_s = sqlite3_column_double(s.stmt, 16);
    r.revision = str(17);
    r.core_version = str(18);
    r.job = Job::FromJson(nlohmann::json::parse(str(19)));  // the columns above are for SQL users
    rows.push_back(std::move(r));
  }
  return rows;
}

std::string ResultStore::InsertFit(const std::string& variant, const std::string& param,
                                   const std::string& material, double value, double j_train, double j_validate,
                                   const nlohmann::json& result) {
  Statement s;
  sqlite3_prepare_v2(db_,
                     "INSERT OR REPLACE INTO fits (variant, param, material, value, j_train, j_validate, result) "
                     "VALUES (?,?,?,?,?,?,?)",
                     -1, &s.stmt, nullptr);
  sqlite3_bind_text(s.stmt, 1, variant.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 2, param.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 3, material.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_double(s.stmt, 4, value);
  sqlite3_bind_double(s.stmt, 5, j_train);
  sqlite3_bind_double(s.stmt, 6, j_validate);
  const std::string text = result.dump();
  sqlite3_bind_text(s.stmt, 7, text.c_str(), -1, SQLITE_TRANSIENT);
  // One statement is its own transaction in SQLite: the row is whole or absent.
  return sqlite3_step(s.stmt) == SQLITE_DONE ? "" : sqlite3_errmsg(db_);
}

std::vector<nlohmann::json> ResultStore::Fits() {
  std::vector<nlohmann::json> out;
  Statement s;
  sqlite3_prepare_v2(db_, "SELECT result FROM fits ORDER BY variant, param, material", -1, &s.stmt, nullptr);
  while (sqlite3_step(s.stmt) == SQLITE_ROW)
    out.push_back(nlohmann::json::parse(reinterpret_cast<const char*>(sqlite3_column_text(s.stmt, 0))));
  return out;
}

std::string ResultStore::MergeFrom(const std::string& other_path) {
  if (!std::filesystem::exists(other_path)) return other_path + ": no such results store";
  std::string escaped;
  for (char c : other_path) escaped += c == '\'' ? std::string("''") : std::string(1, c);
  std::string error = Exec("ATTACH DATABASE '" + escaped + "' AS other;");
  if (!error.empty()) return other_path + ": " + error;
  error = Exec("BEGIN IMMEDIATE; INSERT OR IGNORE INTO jobs SELECT * FROM other.jobs; COMMIT;");
  if (!error.empty()) {
    Exec("ROLLBACK;");
    error = other_path + ": " + error;
  }
  Exec("DETACH DATABASE other;");
  return error;
}

}  // namespace shimmer::experiments
