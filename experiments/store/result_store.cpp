#include "shimmer/experiments/result_store.h"

#include <sqlite3.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <tuple>

#include "shimmer/core/atomic_file.h"

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
  finished_at TEXT DEFAULT (datetime('now')),
  device TEXT, driver TEXT,
  sources TEXT
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
constexpr const char* kFitsByMap = R"sql(
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
std::optional<std::vector<nlohmann::json>> JsonRows(sqlite3* db, const char* sql) {
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
Result<std::vector<T>> TypedRows(sqlite3* db, const char* sql, const std::string& path, const std::string& what) {
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
const char* kJobColumns[] = {"id",
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
                             "sources"};

std::string SqlQuote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::set<std::string> ColumnsOf(sqlite3* db, const std::string& schema, const std::string& table = "jobs") {
  std::set<std::string> columns;
  Statement s;
  if (sqlite3_prepare_v2(db, ("PRAGMA " + schema + ".table_info(" + table + ")").c_str(), -1, &s.stmt, nullptr) !=
      SQLITE_OK)
    return columns;
  while (sqlite3_step(s.stmt) == SQLITE_ROW)
    columns.insert(reinterpret_cast<const char*>(sqlite3_column_text(s.stmt, 1)));
  return columns;
}

bool HasTable(sqlite3* db, const char* schema, const char* name) {
  Statement s;
  const std::string sql = std::string("SELECT 1 FROM ") + schema + ".sqlite_master WHERE type = 'table' AND name = ?";
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s.stmt, nullptr) != SQLITE_OK) return false;
  sqlite3_bind_text(s.stmt, 1, name, -1, SQLITE_STATIC);
  return sqlite3_step(s.stmt) == SQLITE_ROW;
}

// A store's path as an SQLite URI with `query` ("mode=ro", "immutable=1"):
// the characters URIs reserve are percent-encoded, so any file name works.
std::string StoreUri(const std::string& path, const char* query) {
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

bool IsIoError(sqlite3* db) {
  const int code = sqlite3_errcode(db);
  return code == SQLITE_IOERR || code == SQLITE_FULL || code == SQLITE_READONLY || code == SQLITE_CANTOPEN;
}

// SQLite's "disk I/O error" says nothing of the cause; the system's errno does ("File too large").
std::string WithSystemReason(sqlite3* db, std::string message) {
  if (IsIoError(db) && sqlite3_system_errno(db) != 0) message += ": " + SystemReason(sqlite3_system_errno(db));
  return message;
}

Status ExecOn(sqlite3* db, const std::string& sql) {
  char* message = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
    std::string error = WithSystemReason(db, message ? message : "sqlite error");
    sqlite3_free(message);
    return Status::Failure(error, IsIoError(db) ? ErrorCode::kIo : ErrorCode::kBadInput);
  }
  return Ok();
}

}  // namespace

double Metric(const nlohmann::json& metrics, const char* key) {
  return metrics.contains(key) && metrics[key].is_number() ? metrics[key].get<double>() : std::nan("");
}

std::optional<std::pair<double, double>> MetricCi95(const nlohmann::json& metrics, const char* key) {
  const auto ci = metrics.find("ci95");
  if (ci == metrics.end() || !ci->is_object()) return std::nullopt;
  const auto v = ci->find(key);
  if (v == ci->end() || !v->is_array() || v->size() != 2 || !(*v)[0].is_number() || !(*v)[1].is_number())
    return std::nullopt;
  return std::pair((*v)[0].get<double>(), (*v)[1].get<double>());
}

double FlickerIndex(const nlohmann::json& metrics) {
  return metrics.contains("flicker") ? Metric(metrics["flicker"], "flicker_index") : std::nan("");
}

ResultStore::ResultStore(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}
ResultStore::~ResultStore() {
  // WAL only while written: a finished store is left in rollback mode, so that
  // whoever reads it later (report, merge) creates no -wal and -shm beside it.
  // Another connection keeps it in WAL; that one must not be waited for.
  if (writable_) {
    sqlite3_busy_timeout(db_, 0);
    (void)ExecOn(db_, "PRAGMA journal_mode=DELETE;");
  }
  sqlite3_close(db_);
}

Error ResultStore::Failure(const std::string& what) const {
  return Error{IsIoError(db_) ? ErrorCode::kIo : ErrorCode::kBadInput,
               path_ + ": " + what + " (" + WithSystemReason(db_, sqlite3_errmsg(db_)) + ")"};
}

Result<std::unique_ptr<ResultStore>> ResultStore::Open(const std::string& path, Mode mode) {
  using R = Result<std::unique_ptr<ResultStore>>;
  std::error_code ec;
  if (mode == Mode::kReadOnly && !std::filesystem::is_regular_file(path, ec))
    return R::Failure(path + ": no such results store");
  if (std::filesystem::is_directory(path, ec)) return R::Failure(path + ": is a directory, not a results store");
  // Read-only opens by URI. Without a -wal file no connection has the store
  // open (a WAL connection keeps one), and immutable=1 reads the file as it
  // is: no lock, no -shm or -wal created beside it, and it works on a
  // read-only file system. With one, a runner may be writing: mode=ro reads
  // through the WAL.
  auto open = [&](const std::string& uri, int flags) -> sqlite3* {
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(uri.c_str(), &db, flags, nullptr) != SQLITE_OK) {
      sqlite3_close(db);
      return nullptr;
    }
    return db;
  };
  sqlite3* db = nullptr;
  if (mode == Mode::kReadOnly) {
    const int flags = SQLITE_OPEN_READONLY | SQLITE_OPEN_URI;
    const bool live = std::filesystem::exists(path + "-wal", ec);
    db = open(StoreUri(path, live ? "mode=ro" : "immutable=1"), flags);
  } else {
    db = open(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  }
  if (!db) return R::Failure(path + ": cannot open the results store", ErrorCode::kIo);
  std::unique_ptr<ResultStore> store(new ResultStore(db, path));
  sqlite3_busy_timeout(db, 10000);
  if (mode == Mode::kReadOnly) {
    const std::set<std::string> columns = ColumnsOf(db, "main");
    if (!columns.count("id") || !columns.count("job"))
      return R::Failure(path + ": not a shimmer results store (it has no jobs table)");
    store->has_device_columns_ = columns.count("device") > 0;
    store->has_sources_column_ = columns.count("sources") > 0;
    store->has_verdict_tables_ = HasTable(db, "main", "shots") && HasTable(db, "main", "benchmarks");
    return store;
  }
  // WAL: a reader (report) never blocks the runner, and a crash mid-write rolls back cleanly.
  if (Status s = store->Exec("PRAGMA journal_mode=WAL;"); !s) return store->Failure("cannot open the results store");
  store->writable_ = true;
  if (Status s = store->Exec(kSchema); !s)
    return store->Failure(s.code() == ErrorCode::kIo ? "cannot write the results store"
                                                     : "not a shimmer results store");
  // Stores from before the device (or sources) columns get them; their old rows read NULL.
  const std::set<std::string> columns = ColumnsOf(db, "main");
  for (const char* column : {"device", "driver", "sources"})
    if (!columns.count(column))
      if (Status s = store->Exec(std::string("ALTER TABLE jobs ADD COLUMN ") + column + " TEXT;"); !s)
        return store->Failure("cannot add the " + std::string(column) + " column");
  if (!ColumnsOf(db, "main", "fits").count("map"))
    if (Status s = store->Exec(kFitsByMap); !s) {
      (void)store->Exec("ROLLBACK;");  // the failure reported is the one above
      return store->Failure("cannot key the fits by normal map");
    }
  return store;
}

Status ResultStore::Exec(const std::string& sql) {
  Status s = ExecOn(db_, sql);
  if (!s) return Status::Failure(path_ + ": " + s.error(), s.code());
  return s;
}

Result<bool> ResultStore::Has(const std::string& id) {
  Statement s;
  if (sqlite3_prepare_v2(db_, "SELECT 1 FROM jobs WHERE id = ?", -1, &s.stmt, nullptr) != SQLITE_OK)
    return Failure("cannot read the jobs");
  sqlite3_bind_text(s.stmt, 1, id.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(s.stmt);
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) return Failure("cannot read the jobs");
  return rc == SQLITE_ROW;
}

Status ResultStore::Insert(const JobResult& r) {
  if (Status s = Exec("BEGIN IMMEDIATE;"); !s) return s;
  Statement s;
  std::string columns, marks;
  for (const char* c : kJobColumns) {
    if (std::string_view(c) == "finished_at") continue;
    columns += (columns.empty() ? "" : ", ") + std::string(c);
    marks += marks.empty() ? "?" : ",?";
  }
  const std::string sql = "INSERT OR REPLACE INTO jobs (" + columns + ") VALUES (" + marks + ")";
  if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &s.stmt, nullptr) != SQLITE_OK) {
    Error e = Failure("cannot write a job");
    (void)Exec("ROLLBACK;");
    return e;
  }
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
  for (const char* key : {"tv_ratio", "tv_err", "energy_bias", "temporal_diff_err", "relmse"})
    real(Metric(r.metrics, key));
  real(FlickerIndex(r.metrics));
  text(r.metrics.dump());
  text(r.job.ToJson().dump());
  real(r.gpu_ms_per_frame);
  real(r.wall_s);
  text(r.revision);
  text(r.core_version);
  text(r.device);
  text(r.driver);
  if (r.sources.is_null())
    sqlite3_bind_null(s.stmt, i++);
  else
    text(r.sources.dump());
  if (sqlite3_step(s.stmt) != SQLITE_DONE) {
    Error e = Failure("cannot write job " + r.id);
    (void)Exec("ROLLBACK;");
    return e;
  }
  return Exec("COMMIT;");
}

Result<std::vector<JobResult>> ResultStore::All() { return Select("", ""); }

Result<std::optional<JobResult>> ResultStore::Get(const std::string& id) {
  auto rows = Select("WHERE id = ?", id);
  if (!rows) return rows.failure();
  if (rows->empty()) return std::optional<JobResult>();
  return std::optional<JobResult>(std::move(rows->front()));
}

Result<std::vector<JobResult>> ResultStore::Select(const std::string& where, const std::string& id) {
  using R = Result<std::vector<JobResult>>;
  std::vector<JobResult> rows;
  Statement s;
  const std::string device_columns = has_device_columns_ ? "device, driver" : "NULL, NULL";
  const std::string sources_column = has_sources_column_ ? "sources" : "NULL";
  const std::string sql = "SELECT id, reference_id, metrics, gpu_ms_per_frame, wall_s, revision, core_version, job, " +
                          device_columns + ", " + sources_column + " FROM jobs " + where + " ORDER BY id";
  if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &s.stmt, nullptr) != SQLITE_OK) return Failure("cannot read the jobs");
  if (!id.empty()) sqlite3_bind_text(s.stmt, 1, id.c_str(), -1, SQLITE_TRANSIENT);
  auto str = [&](int c) {
    const unsigned char* t = sqlite3_column_text(s.stmt, c);
    return t ? std::string(reinterpret_cast<const char*>(t)) : std::string();
  };
  int rc;
  while ((rc = sqlite3_step(s.stmt)) == SQLITE_ROW) {
    JobResult r;
    r.id = str(0);
    r.reference_id = str(1);
    try {
      r.metrics = nlohmann::json::parse(str(2));
      // The other columns repeat the job for SQL users; the job JSON is the record.
      r.job = Job::FromJson(nlohmann::json::parse(str(7)));
      if (const std::string sources = str(10); !sources.empty()) r.sources = nlohmann::json::parse(sources);
    } catch (const nlohmann::json::exception&) {
      return R::Failure(path_ + ": job " + r.id + " is damaged (its JSON does not parse)");
    }
    r.gpu_ms_per_frame = sqlite3_column_double(s.stmt, 3);
    r.wall_s = sqlite3_column_double(s.stmt, 4);
    r.revision = str(5);
    r.core_version = str(6);
    r.device = str(8);
    r.driver = str(9);
    rows.push_back(std::move(r));
  }
  if (rc != SQLITE_DONE) return Failure("cannot read the jobs");
  if (!has_verdict_tables_) return rows;
  auto shots = Shots();
  if (!shots) return shots.failure();
  auto costs = Benchmarks();
  if (!costs) return costs.failure();
  std::map<std::string, const ShotCheck*> shot_of;
  for (const ShotCheck& shot : *shots) shot_of[shot.reference_id] = &shot;
  // Costs of one (scene, derivative source, variant, parameters), per device.
  using CostKey = std::tuple<std::string, std::string, std::string, std::map<std::string, double>>;
  std::map<CostKey, std::vector<const BenchmarkCost*>> costs_of;
  for (const BenchmarkCost& c : *costs) costs_of[{c.scene, c.derivatives, c.variant, c.params}].push_back(&c);
  for (JobResult& r : rows) {
    if (auto it = shot_of.find(r.reference_id); it != shot_of.end()) r.shot = *it->second;
    auto it = costs_of.find({r.job.scene, r.job.derivatives, r.job.variant, r.job.params});
    if (it == costs_of.end()) continue;
    // The cost measured on the row's own device when there is one.
    const BenchmarkCost* cost = it->second.front();
    for (const BenchmarkCost* c : it->second)
      if (c->device == r.device) cost = c;
    r.cost = *cost;
  }
  JoinExternalCosts(rows);
  return rows;
}

void JoinExternalCosts(std::vector<JobResult>& rows) {
  // The user's own time per frame, as a one-repetition benchmark on their
  // device; its ratio is to a `none` of the same shot timed on that device.
  auto shot = [](const Job& j) { return std::tuple(j.scene, j.material, j.camera); };
  for (JobResult& r : rows) {
    if (!r.job.external || !(r.job.external->ms_per_frame > 0)) continue;
    BenchmarkCost c;
    c.scene = r.job.scene, c.material = r.job.material, c.camera = r.job.camera;
    c.derivatives = r.job.derivatives, c.variant = r.job.variant;
    c.width = r.job.width, c.height = r.job.height, c.repetitions = 1;
    c.median_ms = c.min_ms = c.max_ms = r.job.external->ms_per_frame;
    c.device = r.job.external->device, c.driver = "external";
    c.ratio_to_none = std::numeric_limits<double>::quiet_NaN();
    r.cost = c;
  }
  for (JobResult& r : rows) {
    if (!r.job.external || !r.cost) continue;
    for (const JobResult& none : rows) {
      if (none.job.variant != "none" || shot(none.job) != shot(r.job) || !none.cost) continue;
      if (none.cost->device != r.cost->device || !(none.cost->median_ms > 0)) continue;
      r.cost->none_median_ms = none.cost->median_ms;
      r.cost->ratio_to_none = r.cost->median_ms / none.cost->median_ms;
      break;
    }
  }
}

Result<bool> ResultStore::HasShot(const std::string& reference_id) {
  Statement s;
  if (sqlite3_prepare_v2(db_, "SELECT 1 FROM shots WHERE reference_id = ?", -1, &s.stmt, nullptr) != SQLITE_OK)
    return Failure("cannot read the shots");
  sqlite3_bind_text(s.stmt, 1, reference_id.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(s.stmt);
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) return Failure("cannot read the shots");
  return rc == SQLITE_ROW;
}

Status ResultStore::InsertShot(const ShotCheck& shot) {
  Statement s;
  if (sqlite3_prepare_v2(db_,
                         "INSERT OR REPLACE INTO shots (reference_id, scene, material, camera, converged, check_json) "
                         "VALUES (?,?,?,?,?,?)",
                         -1, &s.stmt, nullptr) != SQLITE_OK)
    return Failure("cannot write a shot");
  const std::string text = nlohmann::json(shot).dump();
  sqlite3_bind_text(s.stmt, 1, shot.reference_id.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 2, shot.scene.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 3, shot.material.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 4, shot.camera.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_int(s.stmt, 5, shot.converged ? 1 : 0);
  sqlite3_bind_text(s.stmt, 6, text.c_str(), -1, SQLITE_TRANSIENT);
  if (sqlite3_step(s.stmt) != SQLITE_DONE) return Failure("cannot write shot " + shot.reference_id);
  return Ok();
}

Result<std::vector<ShotCheck>> ResultStore::Shots() {
  auto shots = TypedRows<ShotCheck>(db_, "SELECT check_json FROM shots ORDER BY reference_id", path_, "shot");
  if (!shots) return shots;
  for (ShotCheck& shot : *shots) JudgeConvergence(shot);
  return shots;
}

Status ResultStore::InsertBenchmarks(const std::vector<BenchmarkCost>& costs) {
  if (Status s = Exec("BEGIN IMMEDIATE;"); !s) return s;
  for (const BenchmarkCost& c : costs) {
    Statement s;
    if (sqlite3_prepare_v2(db_,
                           "INSERT OR REPLACE INTO benchmarks (scene, derivatives, variant, params, width, height, "
                           "device, median_ms, ratio_to_none, cost_json) VALUES (?,?,?,?,?,?,?,?,?,?)",
                           -1, &s.stmt, nullptr) != SQLITE_OK) {
      Error e = Failure("cannot write a benchmark");
      (void)Exec("ROLLBACK;");
      return e;
    }
    const std::string params = nlohmann::json(c.params).dump(), text = nlohmann::json(c).dump();
    sqlite3_bind_text(s.stmt, 1, c.scene.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.stmt, 2, c.derivatives.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.stmt, 3, c.variant.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s.stmt, 4, params.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_int(s.stmt, 5, c.width);
    sqlite3_bind_int(s.stmt, 6, c.height);
    sqlite3_bind_text(s.stmt, 7, c.device.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_double(s.stmt, 8, c.median_ms);
    sqlite3_bind_double(s.stmt, 9, c.ratio_to_none);
    sqlite3_bind_text(s.stmt, 10, text.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(s.stmt) != SQLITE_DONE) {
      Error e = Failure("cannot write a benchmark");
      (void)Exec("ROLLBACK;");
      return e;
    }
  }
  return Exec("COMMIT;");
}

Result<std::vector<BenchmarkCost>> ResultStore::Benchmarks() {
  return TypedRows<BenchmarkCost>(
      db_, "SELECT cost_json FROM benchmarks ORDER BY scene, derivatives, variant, params, device", path_, "benchmark");
}

Result<ResultStore::Pruned> ResultStore::PruneStale(const std::set<std::string>& current_jobs,
                                                   const std::set<std::string>& current_costs, bool dry_run) {
  auto rows = All();
  if (!rows) return rows.failure();
  Pruned p;
  std::vector<std::string> doomed;
  std::set<std::string> kept_references;
  for (const JobResult& r : *rows) {
    if (r.job.external || current_jobs.count(r.id)) {
      ++p.kept_jobs;
      if (r.job.external) ++p.kept_external;
      kept_references.insert(r.reference_id);
    } else {
      doomed.push_back(r.id);
    }
  }
  if (p.kept_jobs == p.kept_external && !doomed.empty())
    return Result<Pruned>::Failure(path_ +
                                   ": no job of this store is one this shimmer would run; pruning would leave only "
                                   "external rows (nothing removed; run the spec with this shimmer first)");
  p.jobs = doomed.size();
  std::vector<std::string> orphan_shots;
  std::vector<BenchmarkCost> stale_costs;
  if (has_verdict_tables_) {
    auto shots = Shots();
    if (!shots) return shots.failure();
    for (const ShotCheck& s : *shots)
      if (!kept_references.count(s.reference_id)) orphan_shots.push_back(s.reference_id);
    auto costs = Benchmarks();
    if (!costs) return costs.failure();
    for (const BenchmarkCost& c : *costs)
      if (!current_costs.count(c.core)) stale_costs.push_back(c);
  }
  p.shots = orphan_shots.size();
  p.benchmarks = stale_costs.size();
  if (dry_run || (p.jobs == 0 && p.shots == 0 && p.benchmarks == 0)) return p;

  if (Status s = Exec("BEGIN IMMEDIATE;"); !s) return s.failure();
  auto run = [&](const char* sql, const std::function<void(sqlite3_stmt*)>& bind) -> Status {
    Statement st;
    bool done = sqlite3_prepare_v2(db_, sql, -1, &st.stmt, nullptr) == SQLITE_OK;
    if (done) {
      bind(st.stmt);
      done = sqlite3_step(st.stmt) == SQLITE_DONE;
    }
    if (done) return Ok();
    Error e = Failure("cannot remove old rows");
    (void)Exec("ROLLBACK;");
    return e;
  };
  auto text = [](sqlite3_stmt* st, int i, const std::string& v) {
    sqlite3_bind_text(st, i, v.c_str(), -1, SQLITE_TRANSIENT);
  };
  for (const std::string& id : doomed)
    if (Status s = run("DELETE FROM jobs WHERE id = ?", [&](sqlite3_stmt* st) { text(st, 1, id); }); !s)
      return s.failure();
  for (const std::string& ref : orphan_shots)
    if (Status s = run("DELETE FROM shots WHERE reference_id = ?", [&](sqlite3_stmt* st) { text(st, 1, ref); }); !s)
      return s.failure();
  for (const BenchmarkCost& c : stale_costs) {
    const std::string params = nlohmann::json(c.params).dump();  // as InsertBenchmarks keys it
    Status s = run(
        "DELETE FROM benchmarks WHERE scene = ? AND derivatives = ? AND variant = ? AND params = ? AND width = ? AND "
        "height = ? AND device = ?",
        [&](sqlite3_stmt* st) {
          text(st, 1, c.scene), text(st, 2, c.derivatives), text(st, 3, c.variant), text(st, 4, params);
          sqlite3_bind_int(st, 5, c.width), sqlite3_bind_int(st, 6, c.height), text(st, 7, c.device);
        });
    if (!s) return s.failure();
  }
  if (Status s = Exec("COMMIT;"); !s) return s.failure();
  // Give the space back; the rows are gone whether or not this succeeds.
  (void)Exec("VACUUM;");
  return p;
}

Status ResultStore::InsertFit(const std::string& variant, const std::string& param, const std::string& material,
                              const std::string& map, double value, double j_train, double j_validate,
                              const nlohmann::json& result) {
  Statement s;
  if (sqlite3_prepare_v2(db_,
                         "INSERT OR REPLACE INTO fits (variant, param, material, value, j_train, j_validate, result, "
                         "map) VALUES (?,?,?,?,?,?,?,?)",
                         -1, &s.stmt, nullptr) != SQLITE_OK)
    return Failure("cannot write a fit");
  sqlite3_bind_text(s.stmt, 1, variant.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 2, param.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 3, material.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_double(s.stmt, 4, value);
  sqlite3_bind_double(s.stmt, 5, j_train);
  sqlite3_bind_double(s.stmt, 6, j_validate);
  const std::string text = result.dump();
  sqlite3_bind_text(s.stmt, 7, text.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 8, map.c_str(), -1, SQLITE_TRANSIENT);
  // One statement is its own transaction in SQLite: the row is whole or absent.
  if (sqlite3_step(s.stmt) != SQLITE_DONE) return Failure("cannot write a fit");
  return Ok();
}

Result<std::vector<nlohmann::json>> ResultStore::Fits() {
  // A store written before any fit ran (or by an older shimmer) has no fits table.
  // A store opened read-only is not migrated: one from before maps has no map column.
  const bool by_map = ColumnsOf(db_, "main", "fits").count("map") > 0;
  auto rows = JsonRows(db_, by_map ? "SELECT result FROM fits ORDER BY variant, param, material, map"
                                   : "SELECT result FROM fits ORDER BY variant, param, material");
  if (!rows) return Result<std::vector<nlohmann::json>>::Failure(path_ + ": a fit row is damaged");
  return *rows;
}

Result<std::size_t> MergeStores(const std::vector<std::string>& inputs, const std::string& output) {
  using R = Result<std::size_t>;
  // Stage every input's rows in memory first: nothing touches `output` until
  // all of them have been read.
  sqlite3* raw = nullptr;
  if (sqlite3_open_v2(":memory:", &raw, SQLITE_OPEN_READWRITE | SQLITE_OPEN_URI, nullptr) != SQLITE_OK) {
    sqlite3_close(raw);
    return R::Failure("cannot open an in-memory database", ErrorCode::kOutOfMemory);
  }
  std::unique_ptr<sqlite3, int (*)(sqlite3*)> db(raw, sqlite3_close);
  if (Status s = ExecOn(db.get(), kSchema); !s) return s.failure();
  std::error_code ec;
  for (const std::string& in : inputs) {
    if (!std::filesystem::is_regular_file(in, ec)) return R::Failure(in + ": no such results store");
    if (std::filesystem::equivalent(in, output, ec)) return R::Failure(in + ": is the output store itself");
    if (Status s = ExecOn(db.get(), "ATTACH DATABASE " + SqlQuote(StoreUri(in, "mode=ro")) + " AS other;"); !s)
      return R::Failure(in + ": cannot open the results store (" + s.error() + ")", s.code());
    const std::set<std::string> columns = ColumnsOf(db.get(), "other");
    std::string select;
    for (const char* c : kJobColumns)
      select += (select.empty() ? "" : ", ") + (columns.count(c) ? std::string(c) : "NULL");
    Status copied = columns.count("id") && columns.count("job")
                        ? ExecOn(db.get(), "INSERT OR IGNORE INTO main.jobs SELECT " + select + " FROM other.jobs;")
                        : Status::Failure("not a shimmer results store (it has no jobs table)");
    for (const char* table : {"shots", "benchmarks"})
      if (copied && HasTable(db.get(), "other", table))
        copied = ExecOn(db.get(),
                        std::string("INSERT OR IGNORE INTO main.") + table + " SELECT * FROM other." + table + ";");
    (void)ExecOn(db.get(), "DETACH DATABASE other;");
    if (!copied) return R::Failure(in + ": " + copied.error());
  }
  const bool existed = std::filesystem::exists(output, ec);
  auto remove_new_output = [&] {
    if (!existed)
      for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(output + suffix, ec);
  };
  {
    // Creates the schema (and WAL) of a new output, or brings an old one up to date.
    auto store = ResultStore::Open(output);
    if (!store) {
      remove_new_output();
      return store.failure();
    }
  }
  auto fail = [&](const std::string& why) -> R {
    remove_new_output();
    return R::Failure(output + ": " + why, ErrorCode::kIo);
  };
  if (Status s = ExecOn(db.get(), "ATTACH DATABASE " + SqlQuote(output) + " AS out;"); !s) return fail(s.error());
  std::string columns;
  for (const char* c : kJobColumns) columns += (columns.empty() ? "" : ", ") + std::string(c);
  Status merged =
      ExecOn(db.get(), "BEGIN IMMEDIATE; INSERT OR IGNORE INTO out.jobs (" + columns + ") SELECT " + columns +
                           " FROM main.jobs; INSERT OR IGNORE INTO out.shots SELECT * FROM main.shots; "
                           "INSERT OR IGNORE INTO out.benchmarks SELECT * FROM main.benchmarks; COMMIT;");
  if (!merged) {
    (void)ExecOn(db.get(), "ROLLBACK;");
    (void)ExecOn(db.get(), "DETACH DATABASE out;");
    return fail(merged.error());
  }
  Statement count;
  std::size_t rows = 0;
  if (sqlite3_prepare_v2(db.get(), "SELECT count(*) FROM out.jobs", -1, &count.stmt, nullptr) == SQLITE_OK &&
      sqlite3_step(count.stmt) == SQLITE_ROW)
    rows = std::size_t(sqlite3_column_int64(count.stmt, 0));
  return rows;
}

Result<std::unique_ptr<StoreLock>> StoreLock::Acquire(const std::string& store_path) {
  using R = Result<std::unique_ptr<StoreLock>>;
  const std::string lock_path = store_path + ".lock";
  // Discard() unlinks a lock file while holding it, so a process that opened
  // the old file may lock it after that; it must find the path gone or
  // replaced, and take the lock again on the file the path now names.
  for (int attempt = 0; attempt < 100; ++attempt) {
    errno = 0;
    bool created = true;
    int fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0 && errno == EEXIST) {
      created = false;
      fd = ::open(lock_path.c_str(), O_RDWR | O_CLOEXEC);
    }
    if (fd < 0) {
      if (errno == ENOENT) continue;  // removed between the two opens
      const ErrorCode code = errno == ENOTDIR ? ErrorCode::kBadInput : ErrorCode::kIo;
      return R::Failure(lock_path + ": cannot create the store's lock file (" + SystemReason(errno) + ")", code);
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int e = errno;
      ::close(fd);
      // Not bad input: the same command works once the other runner is done.
      if (e == EWOULDBLOCK)
        return R::Failure(store_path +
                              ": another shimmer process is running jobs into this store; wait for it to "
                              "finish (one runner per store, lock " +
                              lock_path + ")",
                          ErrorCode::kBusy);
      return R::Failure(lock_path + ": cannot lock (" + SystemReason(e) + ")", ErrorCode::kIo);
    }
    struct stat held {
    }, named{};
    if (::fstat(fd, &held) == 0 && ::stat(lock_path.c_str(), &named) == 0 && held.st_dev == named.st_dev &&
        held.st_ino == named.st_ino)
      return std::unique_ptr<StoreLock>(new StoreLock(fd, lock_path, created));
    ::close(fd);
  }
  return R::Failure(lock_path + ": the lock file keeps being replaced", ErrorCode::kIo);
}

void StoreLock::Discard() {
  if (created_) ::unlink(path_.c_str());
  created_ = false;
}

StoreLock::~StoreLock() { ::close(fd_); }

}  // namespace shimmer::experiments
