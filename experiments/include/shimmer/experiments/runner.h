// Runs a spec's jobs: renders each shared reference once, renders each job,
// measures it with the metrics library and stores one row per job. Finished
// jobs (by id) are skipped, so a run killed at any point resumes losing
// nothing: frames are rendered into "*.partial-<pid>-<n>" directories of
// their process and renamed only when complete, and a row is committed only
// after its metrics exist.
#pragma once

#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/experiments/spec.h"
#include "shimmer/renderer/renderer.h"

namespace shimmer::experiments {

struct RunProgress {
  int done = 0;  // jobs finished in this run (skipped ones included)
  int total = 0;
  int skipped = 0;  // found finished in the store
  double elapsed_s = 0;
  double eta_s = 0;  // from the mean time of the jobs computed so far
  std::string current;
};

struct RunOptions {
  std::string db_path;   // results store
  std::string work_dir;  // frame cache: references and jobs by id
  int shard_index = 0, shard_count = 1;
  bool keep_frames = false;
  int jobs = 1;        // jobs measured at once (each renders, then measures)
  std::string device;  // Vulkan device name substring
  int device_lane = 0;  // set per worker: each renders on a device of its own (vk::ContextOptions::lane)
  // After the jobs: each shot's reference checked at twice the samples per
  // axis (ShotCheck), and the benchmark batches timed (none: skipped).
  bool check_shots = true;
  std::optional<BenchmarkOptions> benchmark;
  std::function<void(const RunProgress&)> progress;
};

struct RunSummary {
  int total = 0, skipped = 0, computed = 0;
  int shots_checked = 0, shots_unconverged = 0;  // checks run by this run, and how many failed
  int benchmarks = 0;                            // batches timed by this run
  int traits_added = 0;                          // stored rows given their scene's traits (SceneTraits)
  int rekeyed = 0;                               // stored rows re-keyed, not measured again (Rekeyable)
  std::optional<Error> error;                    // set when a job failed; the jobs before it are stored
};

// Every job is checked (scene, material, variant, parameters, sizes) before
// the store is opened, so bad input leaves no store behind. The store is
// locked for the run (StoreLock).
RunSummary RunJobs(const std::vector<Job>& jobs, const RunOptions& options);

// The renderer settings of a job; the error names the job's field.
Result<render::RenderSettings> JobSettings(const Job& job, const RunOptions& options);

// One job, measured against its reference (rendered on demand), as the row the
// store keeps. Used by the runner and by sweeps and fits.
Result<JobResult> MeasureJob(const Job& job, const RunOptions& options);

// Where a job's frames and its reference's lie: rendered into the cache
// unless they are there (an external sequence's are the user's, checked
// unchanged). For videos of finished jobs, whose frames the run deleted.
struct JobFrames {
  std::string test, reference;
};
Result<JobFrames> EnsureJobFrames(const Job& job, const RunOptions& options);

// Renders the job's reference into the cache unless it is there.
Status EnsureReference(const Job& job, const RunOptions& options);

// The shot's reference checked: `none` measured against it and against a
// reference with twice the samples per axis (half the tolerance when
// adaptive), compared with the spec's reference.converge.
Result<ShotCheck> CheckShot(const Job& job, const RunOptions& options);

// The variants of one (scene, derivative source), `none` first, each as a job
// of the batch's material and camera (the first job's).
struct BenchmarkBatch {
  std::string scene, derivatives;
  std::vector<Job> jobs;
};
std::vector<BenchmarkBatch> BenchmarkBatches(const std::vector<Job>& jobs);

// Which rows of a store this shimmer would make as they are (the JobId of
// the row's job is its id), and the kernels (BenchmarkCost::core) it would
// time for their jobs; `legacy` counts rows from before per-kernel ids (no
// sources). For report and prune; computing them compiles the kernels the
// rows ran (the on-disk kernel cache makes that fast after a run).
struct CurrentRowSet {
  std::set<std::string> jobs, costs;
  std::size_t legacy = 0;
};
CurrentRowSet FindCurrentRows(const std::vector<JobResult>& rows);

// What `shimmer run` would do with this shard of `jobs` and the store at
// options.db_path (none there: every job is new), rendering nothing. A job
// whose id the store has is done; one that would run says why: "new job",
// or, when the store has a row of the same description (JobDescription), what
// moved (WhyRerun), or that the row is from before per-kernel ids.
struct PlannedJob {
  Job job;
  std::string id;
  std::vector<std::string> why;
};
struct RunPlan {
  std::vector<PlannedJob> to_run;
  std::vector<PlannedJob> to_rekey;  // a stored row today's code would measure alike (Rekeyable)
  int done = 0;
  std::size_t legacy_rows = 0;  // rows of the store from before per-kernel ids
};
inline constexpr const char* kLegacyRowReason = "stored before per-kernel job ids (re-run once)";
inline constexpr const char* kRekeyReason =
    "measured by today's metrics code before the sparkle statistics had a version of their own (re-keyed)";
Result<RunPlan> PlanRun(const std::vector<Job>& jobs, const RunOptions& options);

// Renders every job of `batch` at the benchmark size, interleaved, after one
// warm-up frame each; GPU ms per frame from the renderer's timestamps.
// A ratio of GPU times to `none`'s from paired repetitions: the
// Hodges-Lehmann estimate of the per-repetition log ratios (the median of
// their pairwise means) and the Wilcoxon signed-rank 95 % interval about it
// (lo = hi = 0 with fewer than two pairs). Distribution-free: a frame that a
// slow spell of the machine hit moves the interval by one rank, not by its
// size, where a Student-t interval widens with its square.
struct RatioEstimate {
  double ratio = 0, lo = 0, hi = 0;
  int n = 0;
  // The interval lies within ±precision of the ratio.
  bool Within(double precision) const { return n >= 2 && hi <= ratio * (1 + precision) && lo >= ratio * (1 - precision); }
};
// The rank k (1-based) such that [W_(k), W_(M+1-k)] of the M = n(n+1)/2
// sorted Walsh averages is the two-sided signed-rank interval of coverage at
// least 95 % (exact distribution up to n = 200, normal approximation beyond);
// 0 where n is too small for any interval (n < 6).
int SignedRankCriticalRank(int n);
RatioEstimate PairedRatio(const std::vector<double>& test_ms, const std::vector<double>& none_ms);

Result<std::vector<BenchmarkCost>> RunBenchmark(const BenchmarkBatch& batch, const BenchmarkOptions& bench,
                                                const RunOptions& options);

}  // namespace shimmer::experiments
