// `shimmer run SPEC`: every job of a spec, resumable, optionally one shard.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/experiments/spec.h"

namespace shimmer::cli {

namespace {

struct RunCliOptions {
  std::string spec;
  std::string db;
  std::string work;
  std::string shard = "0/1";
  bool keep_frames = false;
  int jobs = 1;
  std::string device;
  bool no_benchmark = false;
  bool no_check = false;
  bool dry_run = false;
};

// The jobs a run would compute, each with why; nothing is rendered or written.
void PrintPlan(const std::string& spec, const std::string& shard, const experiments::RunPlan& plan) {
  std::printf("%s: %zu jobs in shard %s would run, %d are done\n", spec.c_str(),
              plan.to_run.size(), shard.c_str(), plan.done);
  if (!plan.to_rekey.empty())
    std::printf("%s: %zu stored rows would be re-keyed, not measured again: %s\n", spec.c_str(),
                plan.to_rekey.size(), experiments::kRekeyReason);
  for (const experiments::PlannedJob& p : plan.to_run) {
    std::string why;
    for (const std::string& w : p.why) why += (why.empty() ? "" : "; ") + w;
    const std::string params = p.job.params.empty() ? "" : " " + nlohmann::json(p.job.params).dump();
    std::printf("  %s  %s %s %s %s%s %s: %s\n", p.id.c_str(), p.job.scene.c_str(), p.job.material.c_str(),
                p.job.camera.c_str(), p.job.variant.c_str(), params.c_str(), p.job.derivatives.c_str(), why.c_str());
  }
}

std::string Duration(double s) {
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%dh%02dm", int(s / 3600), int(s / 60) % 60);
  else
    std::snprintf(buf, sizeof buf, "%dm%02ds", int(s / 60), int(s) % 60);
  return buf;
}

void PrintProgress(const experiments::RunProgress& p, bool tty) {
  const int width = 30;
  const int filled = p.total ? width * p.done / p.total : width;
  std::string bar(filled, '#');
  bar.resize(width, '.');
  std::fprintf(stderr, "%s[%s] %d/%d jobs, %d left (%d already done), elapsed %s, ETA %s  %s%s", tty ? "\r" : "",
               bar.c_str(), p.done, p.total, p.total - p.done, p.skipped, Duration(p.elapsed_s).c_str(),
               Duration(p.eta_s).c_str(), p.current.c_str(), tty ? "\033[K" : "\n");
  if (tty && p.done == p.total) std::fprintf(stderr, "\n");
}

void Run(const RunCliOptions& o) {
  const experiments::Spec spec = Take(experiments::LoadSpec(o.spec));
  experiments::RunOptions ro;
  if (!experiments::ParseShard(o.shard, &ro.shard_index, &ro.shard_count))
    throw UsageError("--shard must be i/n with 0 <= i < n, got '" + o.shard + "'");
  if (o.jobs < 1 || o.jobs > 64) throw UsageError("--jobs must be between 1 and 64, got " + std::to_string(o.jobs));
  NewDirectories dirs;
  StorePaths(spec.name, o.db, o.work, "results.db", &ro, &dirs);
  ro.keep_frames = o.keep_frames;
  ro.jobs = o.jobs;
  ro.device = o.device;
  ro.check_shots = !o.no_check;
  if (!o.no_benchmark) ro.benchmark = spec.benchmark;
  const bool tty = isatty(fileno(stderr));
  // A log (not a terminal) gets a line per computed job, not one per job
  // found done: a resumed run would otherwise write a line per stored row.
  ro.progress = [tty, skipped = std::make_shared<int>(0)](const experiments::RunProgress& p) {
    const bool found_done = p.skipped != *skipped;
    *skipped = p.skipped;
    if (!tty && found_done && p.done != p.total) return;
    PrintProgress(p, tty);
  };
  const auto jobs = experiments::ExpandJobs(spec);
  const experiments::RunPlan plan = Take(experiments::PlanRun(jobs, ro));
  if (o.dry_run) {
    PrintPlan(spec.name, o.shard, plan);
    return;
  }
  if (plan.legacy_rows)
    std::fprintf(stderr,
                 "shimmer: %s: %zu rows were keyed by the shading core's text (before per-kernel job ids); their "
                 "jobs run once more, and `shimmer prune %s` removes the old rows afterwards\n",
                 ro.db_path.c_str(), plan.legacy_rows, ro.db_path.c_str());
  const experiments::RunSummary s = experiments::RunJobs(jobs, ro);
  if (s.error) throw CommandError(*s.error);
  dirs.Keep();
  std::printf("%s: %d jobs in shard %s (%d computed, %d already done) -> %s\n", spec.name.c_str(), s.total,
              o.shard.c_str(), s.computed, s.skipped, ro.db_path.c_str());
  if (s.shots_checked)
    std::printf("%s: %d shot references checked at twice the samples per axis, %d unconverged\n", spec.name.c_str(),
                s.shots_checked, s.shots_unconverged);
  if (s.benchmarks) std::printf("%s: %d benchmark batches timed\n", spec.name.c_str(), s.benchmarks);
  if (s.rekeyed)
    std::printf("%s: %d stored rows re-keyed, not measured again: %s\n", spec.name.c_str(), s.rekeyed,
                experiments::kRekeyReason);
  if (s.traits_added)
    std::printf("%s: %d stored rows given their scene's traits (the report classes shots by them)\n",
                spec.name.c_str(), s.traits_added);
  if (s.shots_unconverged)
    std::fprintf(stderr,
                 "shimmer: warning: %d shots have a reference that moved beyond reference.converge at twice the "
                 "samples; the report marks them unconverged and leaves them out of its recommendations\n",
                 s.shots_unconverged);
}

}  // namespace

void StorePaths(const std::string& spec_name, const std::string& db, const std::string& work,
                const std::string& db_file, experiments::RunOptions* ro, NewDirectories* dirs) {
  const std::filesystem::path base = std::filesystem::path("runs") / spec_name;
  ro->db_path = db.empty() ? (base / db_file).string() : db;
  ro->work_dir = work.empty() ? (base / "frames").string() : work;
  const std::filesystem::path db_dir = std::filesystem::path(ro->db_path).parent_path();
  // The user's flag when they gave the path; the path alone when it is the default.
  if (!db_dir.empty()) dirs->Create(db.empty() ? ro->db_path : "--db " + db, db_dir);
  dirs->Create(work.empty() ? ro->work_dir : "--work " + work, ro->work_dir);
}

void AddRunCommand(CLI::App& app) {
  auto o = std::make_shared<RunCliOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Run every job of a spec (resumes; skips finished jobs)");
  cmd->add_option("spec", o->spec, "Spec JSON file")->required();
  cmd->add_option("--db", o->db, "Results store (default runs/<spec name>/results.db)");
  cmd->add_option("--work", o->work, "Frame cache directory (default runs/<spec name>/frames)");
  cmd->add_option("--shard", o->shard, "Run the deterministic slice i/n of the jobs")->capture_default_str();
  cmd->add_option("--jobs", o->jobs, "Jobs measured at once (each renders on the device, then measures on the CPU)")
      ->capture_default_str();
  cmd->add_flag("--keep-frames", o->keep_frames, "Keep rendered frames after measuring");
  cmd->add_option("--device", o->device, "Vulkan device name substring");
  cmd->add_flag("--no-benchmark", o->no_benchmark, "Skip the timing renders of the spec's benchmark section");
  cmd->add_flag("--no-check", o->no_check,
                "Skip the convergence check of each shot's reference (twice the samples per axis)");
  cmd->add_flag("--dry-run", o->dry_run,
                "List the jobs a run would compute and why (new job, kernel of a variant changed, content or "
                "metrics version changed); render and write nothing");
  cmd->callback([o] { Run(*o); });
}

}  // namespace shimmer::cli
