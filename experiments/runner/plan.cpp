// What a run would do before it does it: which jobs of a spec the store
// holds, which it can re-key and which must run, and why (`run --dry-run`),
// and which rows and costs are current (`prune`).
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <thread>
#include <utility>

#include "runner_parts.h"
#include "shimmer/experiments/runner.h"

namespace shimmer::experiments {

namespace fs = std::filesystem;

CurrentRowSet FindCurrentRows(const std::vector<JobResult>& rows) {
  CurrentRowSet current;
  std::vector<Job> jobs;
  for (const JobResult& r : rows) {
    if (r.sources.is_null() && !r.job.external) ++current.legacy;
    // An external sequence's row is current while its id is today's too:
    // the frames' hashes and the metrics code's version are in it.
    if (JobId(r.job) != r.id) continue;
    current.jobs.insert(r.id);
    if (!r.job.external) jobs.push_back(r.job);
  }
  for (const BenchmarkBatch& batch : BenchmarkBatches(jobs))
    for (std::size_t k = 0; k < batch.jobs.size(); ++k) current.costs.insert(BenchmarkKernels(batch, k));
  return current;
}

namespace {

// A kernel's first JobId canonicalizes it (about 0.7 s, then kept on disk):
// made here on `threads` threads, so that a run from an empty kernel cache
// (258 kernels in the standard spec) does not spend its first minutes on
// one core. Failures are left to the caller's own JobId, which names the job.
void PrimeJobSources(const std::vector<Job>& jobs, int threads) {
  if (threads < 2) return;
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t k = next++; k < jobs.size(); k = next++)
      if (!jobs[k].external) (void)SourcesOf(jobs[k]);
  };
  std::vector<std::thread> helpers;
  for (int i = 1; i < threads; ++i) helpers.emplace_back(work);
  work();
  for (std::thread& t : helpers) t.join();
}

}  // namespace

Result<RunPlan> PlanRun(const std::vector<Job>& all_jobs, const RunOptions& options) {
  RunPlan plan;
  std::vector<JobResult> rows;
  std::error_code ec;
  if (fs::exists(options.db_path, ec)) {
    auto store = ResultStore::Open(options.db_path, ResultStore::Mode::kReadOnly);
    if (!store) return store.failure();
    auto all = (*store)->All();
    if (!all) return all.failure();
    rows = std::move(*all);
  }
  std::set<std::string> ids;
  // Every stored version of a description: a store keeps the rows of
  // earlier code beside the current ones (`shimmer prune` drops them).
  std::map<std::string, std::vector<const JobResult*>> by_description;
  for (const JobResult& r : rows) {
    ids.insert(r.id);
    if (r.sources.is_null() && !r.job.external) ++plan.legacy_rows;
    by_description[JobDescription(r.job)].push_back(&r);
  }
  const std::vector<Job> shard = ShardOf(all_jobs, options.shard_index, options.shard_count);
  PrimeJobSources(shard, options.jobs);
  for (const Job& job : shard) {
    PlannedJob planned{job, JobId(job), {}};  // SourcesOf below reads the same memo
    if (ids.count(planned.id)) {
      ++plan.done;
      continue;
    }
    const auto it = by_description.find(JobDescription(job));
    auto now = SourcesOf(job);
    if (!now) return Prefixed("job " + job.scene + " " + job.material + " " + job.camera + " " + job.variant,
                              now.failure());
    if (it == by_description.end()) {
      planned.why = {"new job"};
    } else {
      // What changed since the closest stored version: a row with sources
      // before a legacy one (it says more), then the fewest reasons.
      std::pair<bool, std::size_t> closest{true, std::numeric_limits<std::size_t>::max()};
      const bool rekey = std::any_of(it->second.begin(), it->second.end(), [&](const JobResult* stored) {
        return Rekeyable(job, stored->sources, *now);
      });
      if (rekey) {
        planned.why = {kRekeyReason};
        plan.to_rekey.push_back(std::move(planned));
        continue;
      }
      for (const JobResult* stored : it->second) {
        const bool legacy = stored->sources.is_null();
        std::vector<std::string> why = legacy ? std::vector<std::string>{kLegacyRowReason}
                                              : WhyRerun(job, JobSources::FromJson(stored->sources), *now);
        if (const std::pair<bool, std::size_t> rank{legacy, why.size()}; rank < closest)
          closest = rank, planned.why = std::move(why);
      }
    }
    if (planned.why.empty()) planned.why = {"new job"};
    plan.to_run.push_back(std::move(planned));
  }
  return plan;
}

}  // namespace shimmer::experiments
