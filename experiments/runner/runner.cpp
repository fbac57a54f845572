#include "shimmer/experiments/runner.h"

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

#include "shimmer/core/sequence_file.h"

#include "shimmer/metrics/metrics_report.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::experiments {

namespace fs = std::filesystem;

namespace {

// Renders into dir.partial and renames: a directory under its final name is
// always a complete sequence. Returns its sequence.json.
Result<SequenceFile> RenderInto(const render::RenderSettings& settings, const fs::path& dir) {
  if (fs::exists(dir / "sequence.json")) {
    auto done = ReadSequenceFile(dir / "sequence.json");
    if (done && done->status == SequenceStatus::kComplete) return done;
  }
  const fs::path partial = dir.string() + ".partial";
  std::error_code ec;
  fs::remove_all(partial, ec);
  fs::create_directories(partial.parent_path(), ec);
  auto rendered = render::RenderSequence(settings, partial.string(), {});
  if (!rendered) {
    fs::remove_all(partial, ec);
    return rendered.failure();
  }
  fs::remove_all(dir, ec);
  fs::rename(partial, dir, ec);
  if (ec)
    return Result<SequenceFile>::Failure(dir.string() + ": cannot rename the rendered sequence (" + ec.message() + ")",
                                         ErrorCode::kIo);
  return rendered;
}

fs::path ReferenceDir(const Job& job, const RunOptions& options) {
  return fs::path(options.work_dir) / ("ref-" + ReferenceId(job));
}

}  // namespace

Result<render::RenderSettings> JobSettings(const Job& job, const RunOptions& options) {
  using R = Result<render::RenderSettings>;
  render::RenderSettings s;
  auto scene = scene::LoadScene(job.scene);
  if (!scene) return Prefixed("scene", scene.failure());
  auto material = scene::ParseMaterial(job.material, scene->material);
  if (!material) return material.failure();
  const auto camera = scene::ParseCameraPath(job.camera);
  if (!camera) return R::Failure("camera: unknown camera path '" + job.camera + "'");
  const auto derivatives = shading::ParseDerivativeSource(job.derivatives);
  if (!derivatives)
    return R::Failure("derivatives: '" + job.derivatives + "' must be " + std::string(shading::kDerivativeSourceList));
  s.scene = *scene;
  s.material = *material;
  s.camera = *camera;
  s.fps = job.fps;
  s.width = job.width;
  s.height = job.height;
  s.frames = job.frames;
  s.variant = job.variant;
  s.param_overrides.assign(job.params.begin(), job.params.end());
  s.derivatives = *derivatives;
  s.device = options.device;
  s.compress_exr = options.keep_frames;  // else measured once and deleted
  if (Status v = render::ValidateSettings(s); !v) return v.failure();
  return s;
}

Status EnsureReference(const Job& job, const RunOptions& options) {
  auto reference = JobSettings(job, options);
  if (!reference) return reference.failure();
  reference->variant = "none";
  reference->param_overrides.clear();
  reference->reference_spp = job.reference.spp;
  reference->reference_tolerance = job.reference.tolerance;
  auto rendered = RenderInto(*reference, ReferenceDir(job, options));
  if (!rendered) return Prefixed("reference", rendered.failure());
  return Ok();
}

Result<JobResult> MeasureJob(const Job& job, const RunOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  auto test = JobSettings(job, options);
  if (!test) return test.failure();
  const std::string id = JobId(job), ref_id = ReferenceId(job);
  const fs::path ref_dir = ReferenceDir(job, options);
  const fs::path job_dir = fs::path(options.work_dir) / ("job-" + id);
  if (Status s = EnsureReference(job, options); !s) return s.failure();
  auto rendered = RenderInto(*test, job_dir);
  if (!rendered) return rendered.failure();

  metrics::MetricsOptions mo;
  mo.test = job_dir;
  mo.reference = ref_dir;
  mo.highlight_mask = job.metrics.highlight_mask;
  mo.highlight.threshold = job.metrics.highlight_threshold;
  mo.highlight.empty_falls_back_to_frame = true;
  mo.segment_length = job.metrics.segment;
  auto report = metrics::ComputeMetrics(mo);
  if (!report) return report.failure();
  JobResult r;
  r.id = id;
  r.reference_id = ref_id;
  r.job = job;
  r.metrics = metrics::ToJson(*report);
  r.gpu_ms_per_frame = rendered->MeanGpuMs();
  r.revision = render::SourceRevision();
  r.core_version = ShadingCoreVersion();
  r.device = rendered->device;
  r.driver = rendered->driver;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!options.keep_frames) {
    std::error_code ec;
    fs::remove_all(job_dir, ec);
  }
  return r;
}

RunSummary RunJobs(const std::vector<Job>& all_jobs, const RunOptions& options) {
  RunSummary summary;
  const std::vector<Job> jobs = ShardOf(all_jobs, options.shard_index, options.shard_count);
  summary.total = int(jobs.size());
  // Bad input is found before anything is created.
  for (const Job& job : jobs) {
    auto settings = JobSettings(job, options);
    if (!settings) {
      summary.error = Prefixed(
          "job " + JobId(job) + " (" + job.scene + " " + job.material + " " + job.camera + " " + job.variant + ")",
          settings.failure());
      return summary;
    }
  }
  auto lock = StoreLock::Acquire(options.db_path);
  if (!lock) {
    summary.error = lock.failure();
    return summary;
  }
  std::error_code exists_ec;
  const bool store_existed = fs::exists(options.db_path, exists_ec);
  auto opened = ResultStore::Open(options.db_path);
  if (!opened) {
    std::error_code ec;
    if (!store_existed)
      for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(options.db_path + suffix, ec);
    (*lock)->Discard();
    summary.error = opened.failure();
    return summary;
  }
  std::unique_ptr<ResultStore> store = std::move(*opened);
  // One lock per shared reference, so two workers never render the same one.
  std::map<std::string, std::mutex> reference_locks;
  for (const Job& job : jobs) reference_locks[ReferenceId(job)];

  const auto start = std::chrono::steady_clock::now();
  std::mutex mutex;  // guards the store, the summary and the progress
  RunProgress progress;
  progress.total = summary.total;
  double computed_s = 0;
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};

  auto worker = [&] {
    for (std::size_t k = next++; k < jobs.size() && !failed; k = next++) {
      const Job& job = jobs[k];
      const std::string id = JobId(job);
      const std::string what = job.scene + " " + job.material + " " + job.camera + " " + job.variant;
      Result<bool> done = false;
      {
        std::lock_guard<std::mutex> lock(mutex);
        done = store->Has(id);
      }
      auto stop = [&](const Error& e) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!failed.exchange(true)) summary.error = Prefixed("job " + id + " (" + what + ")", e);
      };
      if (!done) return stop(done.failure());
      double seconds = 0;
      if (!*done) {
        const auto t0 = std::chrono::steady_clock::now();
        Status reference = Ok();
        {
          std::lock_guard<std::mutex> lock(reference_locks.at(ReferenceId(job)));
          reference = EnsureReference(job, options);
        }
        if (!reference) return stop(reference.failure());
        auto measured = MeasureJob(job, options);
        if (!measured) return stop(measured.failure());
        Status inserted = Ok();
        {
          std::lock_guard<std::mutex> lock(mutex);
          inserted = store->Insert(*measured);
        }
        if (!inserted) return stop(inserted.failure());
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      }
      std::lock_guard<std::mutex> lock(mutex);
      if (*done)
        ++summary.skipped;
      else
        ++summary.computed, computed_s += seconds;
      ++progress.done;
      progress.skipped = summary.skipped;
      progress.current = what;
      progress.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const int workers = std::max(1, options.jobs);
      progress.eta_s =
          summary.computed ? computed_s / summary.computed * (progress.total - progress.done) / workers : 0;
      if (options.progress) options.progress(progress);
    }
  };
  std::vector<std::thread> threads;
  for (int i = 1; i < std::max(1, options.jobs); ++i) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  if (failed) {
    // A store this run created and put nothing into is not left behind.
    store.reset();
    if (!store_existed && summary.computed == 0) {
      std::error_code ec;
      for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(options.db_path + suffix, ec);
      (*lock)->Discard();
    }
    return summary;
  }

  if (!options.keep_frames) {
    std::error_code ec;
    for (const auto& [ref, lock] : reference_locks) fs::remove_all(fs::path(options.work_dir) / ("ref-" + ref), ec);
  }
  return summary;
}

}  // namespace shimmer::experiments
