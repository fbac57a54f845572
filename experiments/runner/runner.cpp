#include "shimmer/experiments/runner.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <utility>

#include <nlohmann/json.hpp>

#include "runner_parts.h"
#include "shimmer/core/sequence_file.h"

#include "shimmer/metrics/metrics_report.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/user_variant.h"

namespace shimmer::experiments {

namespace fs = std::filesystem;

namespace {

// The sequence.json of `dir` when a complete sequence is there.
std::optional<SequenceFile> CompleteSequence(const fs::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir / "sequence.json", ec)) return std::nullopt;
  auto done = ReadSequenceFile(dir / "sequence.json");
  if (done && done->status == SequenceStatus::kComplete) return *done;
  return std::nullopt;
}

// Partial directories of `dir` that a killed process left (its pid is gone):
// they would otherwise pile up in the frame cache.
void RemoveAbandonedPartials(const fs::path& dir) {
  const std::string prefix = dir.filename().string() + ".partial-";
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir.parent_path(), ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const int pid = std::atoi(name.c_str() + prefix.size());
    if (pid > 0 && ::kill(pid, 0) != 0 && errno == ESRCH) fs::remove_all(entry.path(), ec);
  }
}

}  // namespace

// Renders into a partial directory of this process and call of its own, then
// renames it: a directory under its final name is always a complete
// sequence, and two processes rendering the same frames into one frame cache
// (`fit` and `run`, two runs) never write into each other's. The first to
// finish is kept; the other's frames, equal by their id, are dropped.
Result<SequenceFile> RenderInto(const render::RenderSettings& settings, const fs::path& dir) {
  if (auto done = CompleteSequence(dir)) return *done;
  RemoveAbandonedPartials(dir);
  static std::atomic<unsigned> calls{0};
  const fs::path partial =
      dir.string() + ".partial-" + std::to_string(::getpid()) + "-" + std::to_string(calls.fetch_add(1));
  std::error_code ec;
  fs::remove_all(partial, ec);
  fs::create_directories(partial.parent_path(), ec);
  auto rendered = render::RenderSequence(settings, partial.string(), {});
  if (!rendered) {
    fs::remove_all(partial, ec);
    return rendered.failure();
  }
  fs::rename(partial, dir, ec);
  if (ec) {
    if (auto done = CompleteSequence(dir)) {  // another process was first
      fs::remove_all(partial, ec);
      return *done;
    }
    // Something incomplete holds the name (a run of an older shimmer): ours replaces it.
    std::error_code removed, renamed;
    fs::remove_all(dir, removed);
    fs::rename(partial, dir, renamed);
    if (renamed) {
      fs::remove_all(partial, ec);
      return Result<SequenceFile>::Failure(
          dir.string() + ": cannot rename the rendered sequence (" + renamed.message() + ")", ErrorCode::kIo);
    }
  }
  return rendered;
}

fs::path ReferenceDirectory(const Job& job, const RunOptions& options) {
  return fs::path(options.work_dir) / ("ref-" + ReferenceId(job));
}

Result<render::RenderSettings> ReferenceSettings(const Job& job, const RunOptions& options) {
  auto reference = ReferenceSettingsOf(job);
  if (!reference) return reference.failure();
  reference->device = options.device;
  reference->device_lane = options.device_lane;
  reference->compress_exr = options.keep_frames;
  return reference;
}

Result<metrics::MetricsReport> MeasureAgainst(const Job& job, const fs::path& test, const fs::path& reference,
                                              const fs::path& mask) {
  metrics::MetricsOptions mo;
  mo.test = test;
  mo.reference = reference;
  if (!mask.empty()) {
    mo.mask_file = mask;
  } else {
    mo.highlight_mask = job.metrics.highlight_mask;
    mo.highlight.threshold = job.metrics.highlight_threshold;
    mo.highlight.empty_falls_back_to_frame = true;
  }
  mo.segment_length = job.metrics.segment;
  mo.sparkle_threshold = job.metrics.sparkle_threshold;
  mo.request.fps = job.fps;  // only where the sequence has no sequence.json to say
  return metrics::ComputeMetrics(mo);
}

// The id promised these frames: frames re-rendered since the spec was read
// would store other numbers under it.
Status CheckExternalFrames(const Job& job) {
  const ExternalFrames& files = *job.external;
  for (const auto& [path, hash] : {std::pair{&files.test, &files.test_hash}, {&files.reference, &files.reference_hash}}) {
    auto now = SequenceContentHash(*path);
    if (!now) return now.failure();
    if (*now != *hash) return Status::Failure(*path + ": the frames changed since the spec was read; run again");
  }
  return Ok();
}

// An external sequence measured as it lies: nothing rendered, nothing cached.
Result<JobResult> MeasureExternal(const Job& job) {
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = CheckExternalFrames(job); !s) return s.failure();
  auto report = MeasureAgainst(job, job.external->test, job.external->reference, {});
  if (!report) return report.failure();
  JobResult r;
  r.id = JobId(job);
  r.reference_id = ReferenceId(job);
  r.job = job;
  r.metrics = metrics::ToJson(*report);
  if (report->ci95) r.draws = std::make_shared<const metrics::BootstrapDraws>(report->ci95->draws);
  if (auto sources = SourcesOf(job)) r.sources = sources->ToJson();
  r.gpu_ms_per_frame = job.external->ms_per_frame;
  r.revision = render::SourceRevision();
  r.device = job.external->device;
  r.driver = "external";
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

Result<render::RenderSettings> JobSettings(const Job& job, const RunOptions& options) {
  auto s = RenderSettingsOf(job);
  if (!s) return s.failure();
  s->device = options.device;
  s->device_lane = options.device_lane;
  s->compress_exr = options.keep_frames;  // else measured once and deleted
  return s;
}

Status EnsureReference(const Job& job, const RunOptions& options) {
  auto reference = ReferenceSettings(job, options);
  if (!reference) return reference.failure();
  auto rendered = RenderInto(*reference, ReferenceDirectory(job, options));
  if (!rendered) return Prefixed("reference", rendered.failure());
  return Ok();
}

Result<JobFrames> EnsureJobFrames(const Job& job, const RunOptions& options) {
  if (job.external) {
    if (Status s = CheckExternalFrames(job); !s) return s.failure();
    return JobFrames{job.external->test, job.external->reference};
  }
  auto test = JobSettings(job, options);
  if (!test) return test.failure();
  if (Status s = EnsureReference(job, options); !s) return s.failure();
  const fs::path dir = fs::path(options.work_dir) / ("job-" + FramesId(job));
  if (auto rendered = RenderInto(*test, dir); !rendered) return rendered.failure();
  return JobFrames{dir.string(), ReferenceDirectory(job, options).string()};
}

Result<JobResult> MeasureJob(const Job& job, const RunOptions& options) {
  if (job.external) return MeasureExternal(job);
  const auto t0 = std::chrono::steady_clock::now();
  auto test = JobSettings(job, options);
  if (!test) return test.failure();
  auto sources = SourcesOf(job);
  if (!sources) return sources.failure();
  const fs::path job_dir = fs::path(options.work_dir) / ("job-" + FramesIdFrom(job, *sources));
  if (Status s = EnsureReference(job, options); !s) return s.failure();
  auto rendered = RenderInto(*test, job_dir);
  if (!rendered) return rendered.failure();
  auto report = MeasureAgainst(job, job_dir, ReferenceDirectory(job, options), {});
  if (!report) return report.failure();
  JobResult r;
  r.id = JobIdFrom(job, *sources);
  r.reference_id = ReferenceIdFrom(job, *sources);
  r.job = job;
  r.metrics = metrics::ToJson(*report);
  if (report->ci95) r.draws = std::make_shared<const metrics::BootstrapDraws>(report->ci95->draws);
  r.gpu_ms_per_frame = rendered->MeanGpuMs();
  r.revision = render::SourceRevision();
  r.core_version = sources->test.kernel;
  r.sources = sources->ToJson();
  r.device = rendered->device;
  r.driver = rendered->driver;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!options.keep_frames) {
    std::error_code ec;
    fs::remove_all(job_dir, ec);
  }
  return r;
}

void OnEachLane(const RunOptions& options, const std::function<void(const RunOptions& on_lane)>& work) {
  auto on = [&](int lane) {
    RunOptions on_lane = options;
    on_lane.device_lane = lane;
    work(on_lane);
  };
  std::vector<std::thread> threads;
  for (int i = 1; i < std::max(1, options.jobs); ++i) threads.emplace_back(on, i);
  on(0);
  for (std::thread& t : threads) t.join();
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

namespace {

// Every job's settings (or an external job's frames) are valid; else the
// first problem, naming the job.
Status CheckJobInputs(const std::vector<Job>& jobs, const RunOptions& options) {
  for (const Job& job : jobs) {
    Status settings = Ok();
    if (job.external) {
      settings = CheckExternalFrames(job);
    } else if (auto rendered = JobSettings(job, options); !rendered) {
      settings = rendered.failure();
    }
    if (!settings)
      return Prefixed(
          "job " + JobId(job) + " (" + job.scene + " " + job.material + " " + job.camera + " " + job.variant + ")",
          settings.failure());
  }
  return Ok();
}

// How many of `jobs` the store does not hold yet.
Result<int> JobsToCompute(const std::vector<Job>& jobs, ResultStore& store) {
  int to_compute = 0;
  for (const Job& job : jobs) {
    auto has = store.Has(JobId(job));
    if (!has) return has.failure();
    if (!*has) ++to_compute;
  }
  return to_compute;
}

// Gives job `id`'s stored row its scene's traits when it lacks them.
Status GiveSceneTraits(ResultStore& store, const Job& job, const std::string& id, int* given) {
  const Result<bool> lacks = store.LacksSceneTraits(id);
  if (!lacks) return lacks.failure();
  if (!*lacks) return Ok();
  const auto sources = SourcesOf(job);
  if (!sources) return sources.failure();
  if (Status updated = store.UpdateSources(id, sources->ToJson()); !updated) return updated;
  ++*given;
  return Ok();
}

// Stores a copy of a row of `job` under `id` where the store holds one that
// today's code would measure alike (Rekeyable); whether it did. `stored`:
// the store's rows by description, read once.
Result<bool> RekeyRow(ResultStore& store, const Job& job, const std::string& id,
                      std::optional<std::map<std::string, std::vector<JobResult>>>& stored) {
  if (!stored) {
    auto all = store.All();
    if (!all) return all.failure();
    stored.emplace();
    for (JobResult& r : *all) (*stored)[JobDescription(r.job)].push_back(std::move(r));
  }
  const auto it = stored->find(JobDescription(job));
  if (it == stored->end()) return false;
  const auto now = SourcesOf(job);
  if (!now) return now.failure();
  for (const JobResult& row : it->second) {
    if (!Rekeyable(job, row.sources, *now)) continue;
    JobResult copy = row;
    copy.id = id;
    copy.sources = now->ToJson();
    if (Status inserted = store.Insert(copy); !inserted) return inserted.failure();
    return true;
  }
  return false;
}

// The state the workers of one run share; `mutex` guards the store, the
// summary and the progress.
struct JobWorkers {
  const std::vector<Job>& jobs;
  const RunOptions& options;
  ResultStore& store;
  RunSummary& summary;
  RunProgress& progress;
  std::map<std::string, std::mutex>& reference_locks;
  const std::vector<std::string>& reference_of;  // each job's ReferenceId, made once ("" for external ones)
  int to_compute = 0;
  std::chrono::steady_clock::time_point start;
  // The workers' own state, made here (not by the aggregate initialiser).
  std::mutex mutex{};
  double computed_s = 0;
  std::atomic<bool> failed{false};
  // Which jobs a worker took, and the references a worker is rendering now
  // (guarded by `mutex`): see Claim.
  std::vector<bool> claimed = std::vector<bool>(jobs.size(), false);
  std::size_t first_unclaimed = 0;
  std::map<std::string, int> rendering{};  // reference id -> workers on its shot before it is on disk
  std::set<std::string> rendered{};
  std::optional<std::map<std::string, std::vector<JobResult>>> stored_rows{};  // for RekeyRow

  // The first failure ends the run; the others are dropped.
  void Stop(const std::string& job, const Error& e) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!failed.exchange(true)) summary.error = Prefixed(job, e);
  }

  // Renders and measures the job (its reference first, one worker per
  // reference) and stores its row; the seconds it took.
  Result<double> Compute(std::size_t k, const RunOptions& on_lane, bool& holds_shot) {
    const Job& job = jobs[k];
    const auto t0 = std::chrono::steady_clock::now();
    if (!job.external) {
      std::lock_guard<std::mutex> lock(reference_locks.at(reference_of[k]));
      Status reference = EnsureReference(job, on_lane);
      Release(k, holds_shot, bool(reference));
      if (!reference) return reference.failure();
    }
    auto measured = MeasureJob(job, on_lane);
    if (!measured) return measured.failure();
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (Status inserted = store.Insert(*measured); !inserted) return inserted.failure();
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  // The next job to compute, or none left. The jobs of one shot follow each
  // other and share its reference, which one worker renders while the others
  // would wait on its lock: a worker takes the first job whose reference no
  // other worker is rendering, so that another shot's reference or a job's
  // frames go on beside it, and waits only when nothing else is left.
  struct Claimed {
    std::size_t index;
    bool holds_shot;  // counted in `rendering` until Release
  };
  std::optional<Claimed> Claim() {
    std::lock_guard<std::mutex> lock(mutex);
    while (first_unclaimed < jobs.size() && claimed[first_unclaimed]) ++first_unclaimed;
    if (first_unclaimed >= jobs.size() || failed) return std::nullopt;
    std::size_t pick = first_unclaimed;
    for (std::size_t k = first_unclaimed; k < jobs.size(); ++k) {
      if (claimed[k]) continue;
      if (jobs[k].external || !rendering.count(reference_of[k])) {
        pick = k;
        break;
      }
    }
    claimed[pick] = true;
    Claimed c{pick, false};
    if (!jobs[pick].external && !rendered.count(reference_of[pick])) {
      ++rendering[reference_of[pick]];
      c.holds_shot = true;
    }
    return c;
  }

  // The claimed job no longer holds its shot back: its reference is on disk
  // (`ready`), failed, or the job was found done.
  void Release(std::size_t k, bool& holds_shot, bool ready) {
    if (!holds_shot) return;
    holds_shot = false;
    std::lock_guard<std::mutex> lock(mutex);
    const std::string& reference = reference_of[k];
    if (ready) rendered.insert(reference);
    if (auto it = rendering.find(reference); it != rendering.end() && --it->second <= 0) rendering.erase(it);
  }

  void Count(bool done, double seconds, const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex);
    if (done)
      ++summary.skipped;
    else
      ++summary.computed, computed_s += seconds;
    ++progress.done;
    progress.skipped = summary.skipped;
    progress.current = what;
    progress.elapsed_s = SecondsSince(start);
    const int workers = std::max(1, options.jobs);
    progress.eta_s =
        summary.computed ? computed_s / summary.computed * std::max(0, to_compute - summary.computed) / workers : 0;
    if (options.progress) options.progress(progress);
  }

  // `on_lane`: the run's options with the worker's own device.
  void Work(const RunOptions& on_lane) {
    while (std::optional<Claimed> claim = Claim()) {
      const Job& job = jobs[claim->index];
      const std::string id = JobId(job);
      const std::string what = job.scene + " " + job.material + " " + job.camera + " " + job.variant;
      const std::string who = "job " + id + " (" + what + ")";
      Result<bool> done = false;
      {
        std::lock_guard<std::mutex> lock(mutex);
        done = store.Has(id);
        // A row stored before scene traits were kept gets them: the report
        // classes shots from the store, not from scene files.
        if (done && *done && !job.external)
          if (Status given = GiveSceneTraits(store, job, id, &summary.traits_added); !given) done = given.failure();
        if (done && !*done) {
          done = RekeyRow(store, job, id, stored_rows);
          if (done && *done) ++summary.rekeyed;
        }
      }
      if (!done || *done) Release(claim->index, claim->holds_shot, false);
      if (!done) return Stop(who, done.failure());
      double seconds = 0;
      if (!*done) {
        auto computed = Compute(claim->index, on_lane, claim->holds_shot);
        if (!computed) return Stop(who, computed.failure());
        seconds = *computed;
      }
      Count(*done, seconds, what);
    }
  }
};

// The run's store, created if missing; a store this call created is removed
// again when it cannot be opened.
Result<std::unique_ptr<ResultStore>> OpenRunStore(const RunOptions& options, StoreLock& lock, bool* existed) {
  std::error_code exists_ec;
  *existed = fs::exists(options.db_path, exists_ec);
  auto opened = ResultStore::Open(options.db_path);
  if (!opened) {
    std::error_code ec;
    if (!*existed)
      for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(options.db_path + suffix, ec);
    lock.Discard();
    return opened.failure();
  }
  return std::move(*opened);
}

}  // namespace

RunSummary RunJobs(const std::vector<Job>& all_jobs, const RunOptions& options) {
  RunSummary summary;
  const std::vector<Job> jobs = ShardOf(all_jobs, options.shard_index, options.shard_count);
  summary.total = int(jobs.size());
  // Bad input is found before anything is created.
  if (Status inputs = CheckJobInputs(jobs, options); !inputs) {
    summary.error = inputs.failure();
    return summary;
  }
  auto lock = StoreLock::Acquire(options.db_path);
  if (!lock) {
    summary.error = lock.failure();
    return summary;
  }
  bool store_existed = false;
  auto opened = OpenRunStore(options, **lock, &store_existed);
  if (!opened) {
    summary.error = opened.failure();
    return summary;
  }
  std::unique_ptr<ResultStore> store = std::move(*opened);
  // One lock per shared reference, so two workers never render the same one.
  std::map<std::string, std::mutex> reference_locks;
  std::vector<std::string> reference_of(jobs.size());
  for (std::size_t k = 0; k < jobs.size(); ++k)
    if (!jobs[k].external) reference_locks[reference_of[k] = ReferenceId(jobs[k])];
  // The ETA counts the jobs left to compute, not those the store has.
  const auto counted = JobsToCompute(jobs, *store);
  if (!counted) {
    summary.error = counted.failure();
    return summary;
  }
  RunProgress progress;
  progress.total = summary.total;
  JobWorkers workers{jobs, options, *store, summary, progress, reference_locks, reference_of, *counted,
                     std::chrono::steady_clock::now()};
  OnEachLane(options, [&workers](const RunOptions& on_lane) { workers.Work(on_lane); });
  if (workers.failed) {
    // A store this run created and put nothing into is not left behind.
    store.reset();
    if (!store_existed && summary.computed == 0) {
      std::error_code ec;
      for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(options.db_path + suffix, ec);
      (*lock)->Discard();
    }
    return summary;
  }
  if (options.check_shots) {
    if (Status s = CheckShots(all_jobs, options, *store, &progress, &summary, workers.start); !s) {
      summary.error = s.failure();
      return summary;
    }
  }
  if (options.benchmark && options.benchmark->enabled) {
    if (Status s = RunBenchmarks(all_jobs, *options.benchmark, options, *store, &progress, &summary, workers.start);
        !s) {
      summary.error = s.failure();
      return summary;
    }
  }
  if (!options.keep_frames) {
    std::error_code ec;
    for (const auto& [ref, lock] : reference_locks) fs::remove_all(fs::path(options.work_dir) / ("ref-" + ref), ec);
  }
  return summary;
}

}  // namespace shimmer::experiments
