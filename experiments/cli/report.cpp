// `shimmer report DB -o DIR`: report.md, report.html, report.csv and plots from a results store.
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "shimmer/experiments/fit_report.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/report.h"
#include "shimmer/experiments/output_files.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/metrics/video_grid.h"

namespace shimmer::cli {

namespace {

struct ReportCliOptions {
  std::string db, out, title = "shimmer report";
  bool video = false;
  std::string work, device;
  int slow = 1;
  std::vector<std::string> fits;
};

// A shot table's grid: its reference and its first rows, each job's frames
// rendered again into the cache when the run deleted them.
experiments::ShotVideoWriter GridWriter(const ReportCliOptions& o) {
  experiments::RunOptions ro;
  ro.work_dir = o.work.empty() ? (std::filesystem::path(o.db).parent_path() / "frames").string() : o.work;
  ro.device = o.device;
  return [ro, slow = o.slow](const std::vector<const experiments::JobResult*>& rows,
                             const std::filesystem::path& file) -> Status {
    metrics::GridSequences in;
    in.slow = slow;
    for (const experiments::JobResult* r : rows) {
      if (int(in.tests.size()) == metrics::VideoGrid::kMaxTiles - 1) break;
      auto frames = experiments::EnsureJobFrames(r->job, ro);
      if (!frames) return frames.failure();
      // Rendered rows share the shot's reference; an external table has only its own.
      if (in.reference.empty() || !r->job.external) in.reference = frames->reference;
      in.tests.push_back(frames->test);
      in.labels.push_back(r->job.external ? r->job.variant + " (external)" : r->job.variant);
      for (const auto& [k, v] : r->job.params) in.labels.back() += " " + k + "=" + experiments::FormatNumber(v, "%g");
    }
    auto written = metrics::WriteGridVideo(in, file);
    if (!written) return written.failure();
    return Ok();
  };
}

}  // namespace

void AddReportCommand(CLI::App& app) {
  auto o = std::make_shared<ReportCliOptions>();
  CLI::App* cmd =
      app.add_subcommand("report", "Write report.md, report.html, report.csv and plots from a results store");
  cmd->add_option("db", o->db, "Results store (from shimmer run); only read")->required();
  cmd->add_option("-o,--output", o->out, "Report directory, e.g. results/quick")->required();
  cmd->add_option("--title", o->title, "Heading of report.md")->capture_default_str();
  cmd->add_flag("--video", o->video,
                "One labelled grid MP4 per shot table (reference, up to 8 rows, signed errors, legend); renders "
                "the frames again where the run deleted them");
  cmd->add_option("--work", o->work, "--video: frame cache (default: frames/ beside the store)");
  cmd->add_option("--device", o->device, "--video: Vulkan device name substring");
  cmd->add_option("--slow", o->slow, "--video: write each frame N times (slow motion)")->capture_default_str();
  cmd->add_option("--fits", o->fits,
                  "fit.json of shimmer fit (repeatable): its joint fits join the overview's engine-settings part");
  cmd->callback([o] {
    RequireCreatableDirectory("--output", o->out);
    if (o->slow < 1 || o->slow > 100) throw UsageError("--slow must be 1..100, got " + std::to_string(o->slow));
    auto store = Take(experiments::ResultStore::Open(o->db, experiments::ResultStore::Mode::kReadOnly));
    std::string note;
    auto all = Take(store->All());
    const experiments::CurrentRowSet current = experiments::FindCurrentRows(all);
    const auto rows = experiments::CurrentRows(std::move(all), current.jobs, &note);
    if (rows.empty()) throw UsageError(o->db + ": the results store has no finished jobs");
    std::vector<experiments::JointFit> engine_fits;
    for (const std::string& f : o->fits)
      for (experiments::JointFit& fit : Take(experiments::ReadJointFits(f))) engine_fits.push_back(std::move(fit));
    std::vector<std::string> warnings;
    if (!note.empty()) warnings.push_back(note);
    Check(experiments::WriteReport(rows, o->title, o->out, &warnings,
                                   o->video ? GridWriter(*o) : experiments::ShotVideoWriter{}, engine_fits));
    for (const std::string& w : warnings) std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
    std::printf("report: %s/report.md and %s/report.html\n", o->out.c_str(), o->out.c_str());
  });
}

}  // namespace shimmer::cli
