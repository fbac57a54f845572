// The store's upkeep: pruning rows this shimmer would not make, merging
// stores of shards, and the lock that keeps two writers off one store.
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

Result<ResultStore::Pruned> ResultStore::PruneStale(const std::set<std::string>& current_jobs,
                                                   const std::set<std::string>& current_costs, bool dry_run) {
  auto rows = All();
  if (!rows) return rows.failure();
  Pruned p;
  std::vector<std::string> doomed;
  std::set<std::string> kept_references;
  for (const JobResult& r : *rows) {
    if (current_jobs.count(r.id)) {
      ++p.kept_jobs;
      if (r.job.external) ++p.kept_external;
      kept_references.insert(r.reference_id);
    } else {
      doomed.push_back(r.id);
    }
  }
  if (p.kept_jobs == 0 && !doomed.empty())
    return Result<Pruned>::Failure(path_ +
                                   ": no job of this store is one this shimmer would run; pruning would leave it "
                                   "empty (nothing removed; run the spec with this shimmer first)");
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
