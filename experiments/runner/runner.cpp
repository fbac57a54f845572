#include "runner.h"

#include <chrono>
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

Measured MeasureJob(const Job& job, const RunOptions& options) {
  Measured m;
  const auto t0 = std::chrono::steady_clock::now();
  render::RenderSettings test;
  m.error = SettingsFor(job, options, &test);
  if (!m.error.empty()) return m;
  render::RenderSettings reference = test;
  reference.variant = "none";
  reference.param_overrides.clear();
  reference.reference_spp = job.reference.spp;
  reference.reference_tolerance = job.reference.tolerance;

  const std::string id = JobId(job), ref_id = ReferenceId(job);
  const fs::path ref_dir = fs::path(options.work_dir) / ("ref-" + ref_id);
  const fs::path job_dir = fs::path(options.work_dir) / ("job-" + id);
  m.error = RenderInto(reference, ref_dir);
  if (!m.error.empty()) return m;
  m.error = RenderInto(test, job_dir);
  if (!m.error.empty()) return m;

  metrics::MetricsOptions mo;
  mo.test = job_dir;
  mo.reference = ref_dir;
  mo.highlight_mask = job.metrics.highlight_mask;
  mo.highlight.threshold = job.metrics.highlight_threshold;
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
  const auto start = std::chrono::steady_clock::now();
  RunProgress progress;
  progress.total = summary.total;
  double computed_s = 0;
  std::vector<std::string> references_used;
  for (const Job& job : jobs) {
    const std::string id = JobId(job);
    references_used.push_back(ReferenceId(job));
    progress.current = job.scene + " " + job.material + " " + job.camera + " " + job.variant;
    if (store->Has(id)) {
      ++summary.skipped;
    } else {
      const auto t0 = std::chrono::steady_clock::now();
      Measured m = MeasureJob(job, options);
      if (!m.error.empty()) {
        summary.error = "job " + id + " (" + progress.current + "): " + m.error;
        return summary;
      }
      if (std::string e = store->Insert(m.result); !e.empty()) {
        summary.error = options.db_path + ": " + e;
        return summary;
      }
      ++summary.computed;
      computed_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    ++progress.done;
    progress.skipped = summary.skipped;
    progress.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    progress.eta_s = summary.computed ? computed_s / summary.computed * (progress.total - progress.done) : 0;
    if (options.progress) options.progress(progress);
  }
  if (!options.keep_frames) {
    std::error_code ec;
    for (const std::string& ref : references_used) fs::remove_all(fs::path(options.work_dir) / ("ref-" + ref), ec);
  }
  return summary;
}

}  // namespace shimmer::experiments
