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

#include "store_sql.h"

namespace shimmer::experiments {

using namespace store_sql;


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
    store->has_draws_column_ = columns.count("draws") > 0;
    store->has_verdict_tables_ = HasTable(db, "main", "shots") && HasTable(db, "main", "benchmarks");
    return store;
  }
  // WAL: a reader (report) never blocks the runner, and a crash mid-write rolls back cleanly.
  if (Status s = store->Exec("PRAGMA journal_mode=WAL;"); !s) return store->Failure("cannot open the results store");
  store->writable_ = true;
  if (Status s = store->Exec(kSchema); !s)
    return store->Failure(s.code() == ErrorCode::kIo ? "cannot write the results store"
                                                     : "not a shimmer results store");
  // Stores from before the device (sources, draws) columns get them; their old rows read NULL.
  const std::set<std::string> columns = ColumnsOf(db, "main");
  for (const auto& [name, type] : {std::pair<std::string, std::string>{"device", "TEXT"},
                                   {"driver", "TEXT"},
                                   {"sources", "TEXT"},
                                   {"draws", "BLOB"}})
    if (!columns.count(name))
      if (Status s = store->Exec("ALTER TABLE jobs ADD COLUMN " + name + " " + type + ";"); !s)
        return store->Failure("cannot add the " + name + " column");
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

Result<bool> ResultStore::LacksSceneTraits(const std::string& id) {
  Statement s;
  const char* sql = "SELECT sources IS NOT NULL AND json_extract(sources, '$.scene') IS NULL FROM jobs WHERE id = ?";
  if (sqlite3_prepare_v2(db_, sql, -1, &s.stmt, nullptr) != SQLITE_OK) return Failure("cannot read the jobs");
  sqlite3_bind_text(s.stmt, 1, id.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(s.stmt);
  if (rc != SQLITE_ROW && rc != SQLITE_DONE) return Failure("cannot read the jobs");
  return rc == SQLITE_ROW && sqlite3_column_int(s.stmt, 0) != 0;
}

Status ResultStore::UpdateSources(const std::string& id, const nlohmann::json& sources) {
  Statement s;
  if (sqlite3_prepare_v2(db_, "UPDATE jobs SET sources = ? WHERE id = ?", -1, &s.stmt, nullptr) != SQLITE_OK)
    return Failure("cannot write job " + id);
  const std::string text = sources.dump();
  sqlite3_bind_text(s.stmt, 1, text.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(s.stmt, 2, id.c_str(), -1, SQLITE_TRANSIENT);
  if (sqlite3_step(s.stmt) != SQLITE_DONE) return Failure("cannot write job " + id);
  return Ok();
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
  if (r.draws) {
    const std::string bytes = metrics::EncodeDraws(*r.draws);
    sqlite3_bind_blob(s.stmt, i++, bytes.data(), int(bytes.size()), SQLITE_TRANSIENT);
  } else {
    sqlite3_bind_null(s.stmt, i++);
  }
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
  const std::string draws_column = has_draws_column_ ? "draws" : "NULL";
  const std::string sql = "SELECT id, reference_id, metrics, gpu_ms_per_frame, wall_s, revision, core_version, job, " +
                          device_columns + ", " + sources_column + ", " + draws_column + " FROM jobs " + where +
                          " ORDER BY id";
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
    if (const void* blob = sqlite3_column_blob(s.stmt, 11)) {
      auto draws = metrics::DecodeDraws(
          std::string_view(static_cast<const char*>(blob), size_t(sqlite3_column_bytes(s.stmt, 11))));
      if (!draws) return R::Failure(path_ + ": job " + r.id + " is damaged (its bootstrap draws do not decode)");
      r.draws = std::make_shared<const metrics::BootstrapDraws>(std::move(*draws));
    }
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

}  // namespace shimmer::experiments
