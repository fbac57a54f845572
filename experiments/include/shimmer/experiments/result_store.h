// The results store: one SQLite row per finished job (every parameter, every
// metric, timings, versions), written in a transaction so that a killed run
// never leaves half a row.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <utility>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shimmer/core/result.h"
#include "shimmer/metrics/block_bootstrap.h"
#include "shimmer/experiments/job.h"
#include "shimmer/shading/shading.h"

struct sqlite3;

namespace shimmer::experiments {

// A shot's reference shown converged, not assumed (DESIGN.md, Trust): `none`
// measured against the shot's reference and against one with twice the
// samples per axis (adaptive references: half the tolerance). One per
// reference id, in table `shots`.
struct ShotCheck {
  std::string reference_id;
  std::string scene, material, camera;
  int spp = 0, check_spp = 0;                 // N and 2N per axis (per replicate)
  int frame_stride = 1;                       // measured on frames 0, k, 2k, ... (rows from before: every frame)
  double tolerance = 0, check_tolerance = 0;  // adaptive references
  // Metrics of `none` against the reference at N (as the jobs are measured) and at 2N.
  double tv_ref = 0, tv_ref_check = 0;
  double energy_bias = 0, energy_bias_check = 0;
  double tv_err = 0, tv_err_check = 0;
  // F = mean stderr.Y^2 of each reference: the share of tv_err its own noise
  // adds (docs/metrics.md, tv_err_floor). Rows from before it was kept: 0.
  double tv_err_noise = 0, tv_err_noise_check = 0;
  // Glint shots (a spec with metrics.sparkle_threshold): each reference's
  // sparkles per frame (docs/metrics.md, "Sparkle statistics"), which a
  // reference's own noise inflates where a pixel holds many microdetails and
  // few samples. 0 where not measured (rows from before it was: both 0).
  double sparkle_count = 0, sparkle_count_check = 0;
  // |tv_ref_check / tv_ref - 1|, |energy_bias_check - energy_bias|, the
  // relative change of tv_err less each reference's noise F, and
  // |sparkle_count_check / sparkle_count - 1|.
  double d_tv_ref = 0, d_energy_bias = 0, d_tv_err = 0, d_sparkle_count = 0;
  double tol_energy = 0.02, tol_tv = 0.10;  // the spec's reference.converge
  long long unconverged_pixels = 0;         // pixel-frames of the reference left above its tolerance at max_rounds
  bool converged = false;                   // every change within its tolerance
};

}  // namespace shimmer::experiments
namespace shimmer::shading {
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(InstructionCensus, alu, transcendental, memory, control)
}  // namespace shimmer::shading
namespace shimmer::experiments {

// Cost as a benchmark (DESIGN.md, Trust): dedicated timing renders at the
// benchmark size, every variant of a (scene, derivative source) interleaved
// in one batch after warm-up. One per (scene, derivatives, variant, params,
// size, device), in table `benchmarks`.
struct BenchmarkCost {
  std::string scene, derivatives, variant;
  std::map<std::string, double> params;
  std::string material, camera;  // what the batch rendered (the spec's first material and camera)
  int width = 0, height = 0, repetitions = 0;
  double median_ms = 0, min_ms = 0, max_ms = 0;  // GPU ms per frame over the repetitions
  double none_median_ms = 0;                     // `none` in the same batch
  // The paired per-repetition ratio to `none` (Hodges-Lehmann) and its
  // 95 % interval (RatioEstimate). Older rows: median_ms / none_median_ms
  // and no interval (ratio_lo = ratio_hi = 0).
  double ratio_to_none = 0, ratio_lo = 0, ratio_hi = 0;
  // The half-width its interval was timed to (the spec's
  // benchmark.precision); rows stored before it was kept were timed to 3 %.
  double precision = 0.03;
  std::string device, driver;
  // The kernels it was timed with (BenchmarkKernels): a cost of other
  // kernels is timed again. Older rows: the shading core's text hash.
  std::string core;
  // Static instruction counts of this kernel and of `none`'s in the batch
  // (all 0 in older rows).
  shading::InstructionCensus kernel, none_kernel;
};

// Fills the changes (d_tv_ref, d_energy_bias, d_tv_err, d_sparkle_count) and the verdict of a
// check from its measured metrics and tolerances. A tv_err below 0.1 % of
// tv_ref is measured against that floor: `none` already matches the
// reference there, and a relative change of reference noise means nothing.
// tv_err passes when it holds still, or when its change is the reference's
// own noise converging (tv_err - F holds still). The store re-judges every
// shot it reads, so verdicts follow this rule, not the one of the run that
// measured them (runner/shot_check.cpp).
void JudgeConvergence(ShotCheck& check);

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ShotCheck, reference_id, scene, material, camera, spp, check_spp, frame_stride,
                                                tolerance, check_tolerance, tv_ref, tv_ref_check, energy_bias,
                                                energy_bias_check, tv_err, tv_err_check, tv_err_noise,
                                                tv_err_noise_check, sparkle_count, sparkle_count_check, d_tv_ref,
                                                d_energy_bias, d_tv_err, d_sparkle_count, tol_energy,
                                                tol_tv, unconverged_pixels, converged)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(BenchmarkCost, scene, derivatives, variant, params, material, camera,
                                                width, height, repetitions, median_ms, min_ms, max_ms, none_median_ms,
                                                ratio_to_none, ratio_lo, ratio_hi, precision, device, driver, core,
                                                kernel, none_kernel)

struct JobResult {
  std::string id;
  std::string reference_id;
  Job job;
  nlohmann::json metrics;  // the metrics library's JSON (tv_ratio, tv_err, ...)
  double gpu_ms_per_frame = 0;
  double wall_s = 0;
  std::string revision;
  std::string core_version;  // the kernel that rendered it (JobSources::test.kernel); older rows: the core's text hash
  // JobSources::ToJson of the code that made the row; null for rows from
  // before per-kernel ids (they are re-run once, see `shimmer run`).
  nlohmann::json sources;
  std::string device;  // the Vulkan device that rendered it, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string driver;  // its driver and version, so that merged shards stay distinguishable
  // The metrics' bootstrap draws of tv_err and relmse, for paired
  // comparisons with the shot's other rows; null in external rows and
  // stores measured before them.
  std::shared_ptr<const metrics::BootstrapDraws> draws;
  // Joined when read from a store: the shot's convergence check (by
  // reference_id) and the benchmark cost of this variant on this device.
  std::optional<ShotCheck> shot;
  std::optional<BenchmarkCost> cost;
};

// Gives each external row with a cost (ExternalFrames::ms_per_frame) a
// BenchmarkCost of one repetition on the user's device, with its ratio to a
// `none` of the same shot timed on that device (NaN without one). Part of
// ResultStore::All.
void JoinExternalCosts(std::vector<JobResult>& rows);

// A metric of the metrics library's JSON (e.g. "tv_err"), NaN when absent
// or not a number; FlickerIndex reads flicker.flicker_index.
double Metric(const nlohmann::json& metrics, const char* key);
double FlickerIndex(const nlohmann::json& metrics);
// A metric's 95 % interval, ci95[key] = [lo, hi]; empty when the row has none
// (stores from before intervals).
std::optional<std::pair<double, double>> MetricCi95(const nlohmann::json& metrics, const char* key);

class ResultStore {
 public:
  enum class Mode {
    kReadWrite,  // created when missing, schema brought up to date, WAL journal while open
    kReadOnly,   // must exist; never written, not even its journal mode
  };
  // The error names the file and the cause.
  static Result<std::unique_ptr<ResultStore>> Open(const std::string& path, Mode mode = Mode::kReadWrite);
  ~ResultStore();

  Result<bool> Has(const std::string& id);
  Status Insert(const JobResult& result);
  // Whether job `id`'s row lacks its scene's traits (stored before they
  // were kept), and gives them to it: the row's sources JSON replaced by
  // `sources`, which must describe the same job (same id).
  Result<bool> LacksSceneTraits(const std::string& id);
  Status UpdateSources(const std::string& id, const nlohmann::json& sources);
  Result<std::vector<JobResult>> All();
  Result<std::optional<JobResult>> Get(const std::string& id);

  // Convergence checks, one per reference id (replaced when run again).
  Result<bool> HasShot(const std::string& reference_id);
  Status InsertShot(const ShotCheck& shot);
  Result<std::vector<ShotCheck>> Shots();

  // Benchmark costs, one per (scene, derivatives, variant, params, size, device).
  Status InsertBenchmarks(const std::vector<BenchmarkCost>& costs);  // one transaction
  Result<std::vector<BenchmarkCost>> Benchmarks();

  // Fit results (table `fits`), one row per (variant, parameter, material,
  // normal map; "" for a fit not per map) of a fit, replaced when the fit is
  // run again; `result` is the fit's JSON.
  Status InsertFit(const std::string& variant, const std::string& param, const std::string& material,
                   const std::string& map, double value, double j_train, double j_validate,
                   const nlohmann::json& result);
  Result<std::vector<nlohmann::json>> Fits();

  // A store keeps the rows of every version of the code it ran with (a
  // changed kernel moves the ids of its jobs). PruneStale removes the job rows
  // whose id is not in `current_jobs` (external sequences, which no kernel
  // renders, are kept), the convergence checks no remaining row refers to,
  // and the benchmark costs whose kernels (BenchmarkCost::core) are not in
  // `current_costs`; then compacts the file. One transaction: all or
  // nothing. Refused, with nothing removed, when no job row is current
  // (pruning would empty it). `dry_run` counts without removing.
  struct Pruned {
    std::size_t jobs = 0, shots = 0, benchmarks = 0;  // removed (or, in a dry run, to remove)
    std::size_t kept_jobs = 0, kept_external = 0;
  };
  Result<Pruned> PruneStale(const std::set<std::string>& current_jobs, const std::set<std::string>& current_costs,
                            bool dry_run);

 private:
  explicit ResultStore(sqlite3* db, std::string path);
  Result<std::vector<JobResult>> Select(const std::string& where, const std::string& id);
  Status Exec(const std::string& sql);
  Error Failure(const std::string& what) const;  // names the file and SQLite's reason
  sqlite3* db_;
  std::string path_;
  bool has_device_columns_ = true;
  bool has_sources_column_ = true;
  bool has_draws_column_ = true;
  bool has_verdict_tables_ = true;  // shots and benchmarks (a read-only old store may lack them)
  bool writable_ = false;           // opened kReadWrite and switched to WAL
};

// Joins the jobs of `inputs` into `output` (created when missing; rows whose
// id it already has are kept). All or nothing: every input is read and
// checked first, and a failure leaves `output` as it was. Returns the number
// of jobs in `output` afterwards.
Result<std::size_t> MergeStores(const std::vector<std::string>& inputs, const std::string& output);

// One runner per store: an exclusive lock (flock) on "<store>.lock", held
// while the object lives. A second runner on the same store fails at once,
// with a message saying so, instead of both overwriting each other's frames.
class StoreLock {
 public:
  static Result<std::unique_ptr<StoreLock>> Acquire(const std::string& store_path);
  ~StoreLock();
  StoreLock(const StoreLock&) = delete;
  StoreLock& operator=(const StoreLock&) = delete;
  // Removes the lock file when Acquire created it (the lock stays held until
  // the object goes): for a run that failed before leaving a store behind.
  void Discard();

 private:
  StoreLock(int fd, std::string path, bool created) : fd_(fd), path_(std::move(path)), created_(created) {}
  int fd_;
  std::string path_;
  bool created_;
};

}  // namespace shimmer::experiments
