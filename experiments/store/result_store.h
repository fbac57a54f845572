// The results store: one SQLite row per finished job (every parameter, every
// metric, timings, versions), written in a transaction so that a killed run
// never leaves half a row.
#pragma once

#include <memory>
#include <optional>
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

// A metric of the metrics library's JSON (e.g. "tv_err"), NaN when absent
// or not a number; FlickerIndex reads flicker.flicker_index.
double Metric(const nlohmann::json& metrics, const char* key);
double FlickerIndex(const nlohmann::json& metrics);

class ResultStore {
 public:
  // Opens or creates the store; the error names the file and the cause.
  static std::pair<std::unique_ptr<ResultStore>, std::string> Open(const std::string& path);
  ~ResultStore();

  bool Has(const std::string& id);
  std::string Insert(const JobResult& result);  // error message, empty on success
  std::vector<JobResult> All();
  std::optional<JobResult> Get(const std::string& id);

  // Fit results (table `fits`), one row per (variant, parameter, material) of
  // a fit, replaced when the fit is run again; `result` is the fit's JSON.
  std::string InsertFit(const std::string& variant, const std::string& param, const std::string& material,
                        double value, double j_train, double j_validate, const nlohmann::json& result);
  std::vector<nlohmann::json> Fits();
  // Copies every row of `other_path` not already here (by job id).
  std::string MergeFrom(const std::string& other_path);

 private:
  explicit ResultStore(sqlite3* db);
  std::vector<JobResult> Select(const std::string& where, const std::string& id);
  std::string Exec(const std::string& sql);
  sqlite3* db_;
};

}  // namespace shimmer::experiments
