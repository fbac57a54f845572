#include "runner.h"

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <thread>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "renderer.h"
#include "scene.h"
#include "shimmer/metrics/metrics_report.h"

namespace shimmer::experiments {

namespace fs = std::filesystem;

namespace {

std::string SettingsFor(const Job& job, const RunOptions& options, render::RenderSettings* s) {
  auto scene = scene::LoadScene(job.scene);
  if (!scene.ok()) return scene.error;
  auto material = scene::ParseMaterial(job.material, scene.value.material);
  if (!material.ok()) return material.error;
  s->scene = scene.value;
  s->material = material.value;
  s->camera = job.camera;
  s->fps = job.fps;
  s->width = job.width;
  s->height = job.height;
  s->frames = job.frames;
  s->variant = job.variant;
  s->param_overrides.assign(job.params.begin(), job.params.end());
  s->derivatives = job.derivatives == "analytic"      ? shading::DerivativeSource::kAnalytic
                   : job.derivatives == "quad-coarse" ? shading::DerivativeSource::kQuadCoarse
                                                      : shading::DerivativeSource::kQuadFine;
  s->device = options.device;
  s->compress_exr = options.keep_frames;  // else measured once and deleted
  return "";
}

// Renders into dir.partial and renames: a directory under its final name is
// always a complete sequence.
std::string RenderInto(const render::RenderSettings& settings, const fs::path& dir) {
  if (fs::exists(dir / "sequence.json")) return "";
  const fs::path partial = dir.string() + ".partial";
  std::error_code ec;
  fs::remove_all(partial, ec);
  fs::create_directories(partial.parent_path(), ec);
  std::string error = render::RenderSequence(settings, partial.string(), {});
  if (!error.empty()) {
    fs::remove_all(partial, ec);
    return error;
  }
  fs::remove_all(dir, ec);
  fs::rename(partial, dir, ec);
  if (ec) return dir.string() + ": cannot rename the rendered sequence: " + ec.message();
  return "";
}

double MeanGpuMs(const fs::path& dir) {
  std::ifstream in(dir / "sequence.json");
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.contains("frames")) return 0;
  double sum = 0;
  int n = 0;
  for (const auto& f : j["frames"]) {
    if (f.contains("gpu_ms")) sum += f["gpu_ms"].get<double>(), ++n;
  }
  return n ? sum / n : 0;
}

}  // namespace

fs::path ReferenceDir(const Job& job, const RunOptions& options) {
  return fs::path(options.work_dir) / ("ref-" + ReferenceId(job));
}

std::string EnsureReference(const Job& job, const RunOptions& options) {
  render::RenderSettings reference;
  if (std::string e = SettingsFor(job, options, &reference); !e.empty()) return e;
  reference.variant = "none";
  reference.param_overrides.clear();
  reference.reference_spp = job.reference.spp;
  reference.reference_tolerance = job.reference.tolerance;
  return RenderInto(reference, ReferenceDir(job, options));
}

Measured MeasureJob(const Job& job, const RunOptions& options) {
  Measured m;
  const auto t0 = std::chrono::steady_clock::now();
  render::RenderSettings test;
  m.error = SettingsFor(job, options, &test);
  if (!m.error.empty()) return m;
  const std::string id = JobId(job), ref_id = ReferenceId(job);
  const fs::path ref_dir = ReferenceDir(job, options);
  const fs::path job_dir = fs::path(options.work_dir) / ("job-" + id);
  m.error = EnsureReference(job, options);
  if (!m.error.empty()) return m;
  m.error = RenderInto(test, job_dir);
  if (!m.error.empty()) return m;

  metrics::MetricsOptions mo;
  mo.test = job_dir;
  mo.reference = ref_dir;
  mo.highlight_mask = job.metrics.highlight_mask;
  mo.highlight.threshold = job.metrics.highlight_threshold;
  mo.highlight.empty_falls_back_to_frame = true;
  mo.segment_length = job.metrics.segment;
  auto report = metrics::ComputeMetrics(mo);
  if (!report.ok()) {
    m.error = report.error();
    return m;
  }
  m.result.id = id;
  m.result.reference_id = ref_id;
  m.result.job = job;
  m.result.metrics = metrics::ToJson(report.value());
  m.result.gpu_ms_per_frame = MeanGpuMs(job_dir);
  m.result.revision = render::SourceRevision();
  m.result.core_version = ShadingCoreVersion();
  m.result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!options.keep_frames) {
    std::error_code ec;
    fs::remove_all(job_dir, ec);
  }
  return m;
}

RunSummary RunJobs(const std::vector<Job>& all_jobs, const RunOptions& options) {
  RunSummary summary;
  const std::vector<Job> jobs = ShardOf(all_jobs, options.shard_index, options.shard_count);
  summary.total = int(jobs.size());
  auto [store, error] = ResultStore::Open(options.db_path);
  if (!store) {
    summary.error = error;
    return summary;
  }
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
      bool done;
      {
        std::lock_guard<std::mutex> lock(mutex);
        done = store->Has(id);
      }
      double seconds = 0;
      if (!done) {
        const auto t0 = std::chrono::steady_clock::now();
        std::string e;
        {
          std::lock_guard<std::mutex> lock(reference_locks.at(ReferenceId(job)));
          e = EnsureReference(job, options);
        }
        Measured m;
        if (e.empty()) m = MeasureJob(job, options), e = m.error;
        std::lock_guard<std::mutex> lock(mutex);
        if (e.empty()) e = store->Insert(m.result);
        if (!e.empty()) {
          if (!failed.exchange(true)) summary.error = "job " + id + " (" + what + "): " + e;
          return;
        }
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      }
      std::lock_guard<std::mutex> lock(mutex);
      if (done) ++summary.skipped; else ++summary.computed, computed_s += seconds;
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
  if (failed) return summary;

  if (!options.keep_frames) {
    std::error_code ec;
    for (const auto& [ref, lock] : reference_locks) fs::remove_all(fs::path(options.work_dir) / ("ref-" + ref), ec);
  }
  return summary;
}

}  // namespace shimmer::experiments
