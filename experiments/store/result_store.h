// The results store: one SQLite row per finished job (every parameter, every
// metric, timings, versions), written in a transaction so that a killed run
// never leaves half a row.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "job.h"

struct sqlite3;

namespace shimmer::experiments {

struct JobResult {
  std::string id;
  std::string reference_id;
  Job job;
  nlohmann::json metrics;  // the metrics library's JSON (tv_ratio, tv_err, ...)
  double gpu_ms_per_frame = 0;
  double wall_s = 0;
  std::string revision;
  std::string core_version;
};

class ResultStore {
 public:
  // Opens or creates the store; the error names the file and the cause.
  static std::pair<std::unique_ptr<ResultStore>, std::string> Open(const std::string& path);
  ~ResultStore();

  bool Has(const std::string& id);
  std::string Insert(const JobResult& result);  // error message, empty on success
  std::vector<JobResult> All();
  // Copies every row of `other_path` not already here (by job id).
  std::string MergeFrom(const std::string& other_path);

 private:
  explicit ResultStore(sqlite3* db);
  std::string Exec(const std::string& sql);
  sqlite3* db_;
};

}  // namespace shimmer::experiments
