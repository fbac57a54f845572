// What the runner's pieces share (runner.cpp: jobs; shot_check.cpp: the
// reference's convergence; benchmark.cpp: timing renders).
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/core/sequence_file.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/metrics/metrics_report.h"
#include "shimmer/renderer/renderer.h"

namespace shimmer::experiments {

// Renders into a partial directory of its own and renames it: a directory
// under its final name is always a complete sequence. A complete one already
// there (or one another process finishes first) is kept.
Result<SequenceFile> RenderInto(const render::RenderSettings& settings, const std::filesystem::path& dir);

std::filesystem::path ReferenceDirectory(const Job& job, const RunOptions& options);

// The settings of the job's reference (`none`, supersampled, with replicates).
Result<render::RenderSettings> ReferenceSettings(const Job& job, const RunOptions& options);

// The job's metrics of `test` against `reference`: over the job's highlight
// region, or over `mask` (a PNG) when given.
Result<metrics::MetricsReport> MeasureAgainst(const Job& job, const std::filesystem::path& test,
                                              const std::filesystem::path& reference,
                                              const std::filesystem::path& mask);

// What a cost of batch member `k` was timed with: its kernel and the kernel
// of the batch's `none` (the ratio's denominator). A cost of other kernels
// is timed again; a comment edit in a shader times nothing again.
std::string BenchmarkKernels(const BenchmarkBatch& batch, std::size_t k);

// Runs `work` on `options.jobs` workers, this thread one of them, each with
// a Vulkan device of its own (RunOptions::device_lane): lavapipe leaves
// cores idle at a dispatch's tail that a second device fills.
void OnEachLane(const RunOptions& options, const std::function<void(const RunOptions& on_lane)>& work);

double SecondsSince(std::chrono::steady_clock::time_point start);
// One check per shot (reference id) that the store lacks (shot_check.cpp),
// on `options.jobs` workers; shots are dealt to shards by index.
Status CheckShots(const std::vector<Job>& all_jobs, const RunOptions& options, ResultStore& store,
                  RunProgress* progress, RunSummary* summary, std::chrono::steady_clock::time_point start);
// Times this shard's benchmark batches that the store lacks (benchmark.cpp).
Status RunBenchmarks(const std::vector<Job>& all_jobs, const BenchmarkOptions& bench, const RunOptions& options,
                     ResultStore& store, RunProgress* progress, RunSummary* summary,
                     std::chrono::steady_clock::time_point start);

}  // namespace shimmer::experiments
