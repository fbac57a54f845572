// `shimmer fit SPEC`: the spec's `fit` section: per material and variant the
// parameter value that minimises the objective, validated on held-out shots,
// written as fit.md / fit.json / J(p) plots and as rows of the store.
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "shimmer/experiments/fit_report.h"
#include "shimmer/experiments/fit_run.h"
#include "shimmer/experiments/spec.h"

namespace shimmer::cli {

namespace {

struct FitCliOptions {
  std::string spec, db, work, out, device, from_json;
  std::vector<std::string> variant_files;
  bool keep_frames = false;
};

void Run(const FitCliOptions& o) {
  experiments::Spec spec = Take(experiments::LoadSpec(o.spec));
  if (spec.fits.empty()) throw UsageError(o.spec + ": the spec has no \"fit\" section");
  // Each file joins every fit entry, as if the spec listed it there.
  for (const std::string& file : o.variant_files) {
    const std::string name = UserVariantName(file);
    Take(experiments::AddUserVariant(&spec, file, name));
    for (experiments::FitConfig& config : spec.fits) {
      if (Status s = experiments::CheckFitVariant(spec, name, config.param, config.lo, config.hi); !s)
        throw UsageError("--variant-file " + file + ": " + s.error());
      config.variants.push_back(name);
    }
  }
  // Found before the fits: the report would be lost after hours of renders.
  const std::string out = o.out.empty() ? (std::filesystem::path("results") / spec.name).string() : o.out;
  RequireCreatableDirectory(o.out.empty() ? "the report directory" : "--out", out);
  if (!o.from_json.empty()) {
    // The report again, from the fits a run wrote: nothing rendered.
    if (!o.variant_files.empty()) throw UsageError("--from-json takes the fits as they are: no --variant-file");
    const experiments::FitOutcome outcome = Take(experiments::ReadFitOutcome(o.from_json));
    std::vector<std::string> warnings;
    Check(experiments::WriteFitReport(outcome, spec, out, &warnings));
    for (const std::string& w : warnings) std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
    std::printf("fit: %s/fit.md (from %s, nothing rendered)\n", out.c_str(), o.from_json.c_str());
    return;
  }
  experiments::RunOptions ro;
  NewDirectories dirs;
  StorePaths(spec.name, o.db, o.work, "fit.db", &ro, &dirs);
  ro.keep_frames = o.keep_frames;
  ro.device = o.device;
  // Results on stdout, progress on stderr: `shimmer fit spec.json > fits.txt` keeps the answers.
  const experiments::FitOutcome outcome = experiments::RunFits(
      spec, ro, [](const std::string& line) { std::printf("%s\n", line.c_str()), std::fflush(stdout); },
      [](const std::string& line) { std::fprintf(stderr, "shimmer: %s\n", line.c_str()); });
  if (outcome.error) throw CommandError(*outcome.error);
  dirs.Keep();
  for (const experiments::FitLaw& l : outcome.laws) {
    std::printf("%s, %s materials: %s(alpha) = %.4g * alpha^%.4g; log residuals:", l.variant.c_str(), l.ndf.c_str(),
                l.param.c_str(), l.law.a, l.law.b);
    for (std::size_t i = 0; i < l.alpha.size(); ++i)
      std::printf(" %s %+.3f", l.materials[i].c_str(), l.law.residuals[i]);
    std::printf("\n");
  }
  std::vector<std::string> warnings;
  Check(experiments::WriteFitReport(outcome, spec, out, &warnings));
  for (const std::string& w : warnings) std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
  std::printf("fit: %s/fit.md (rows in %s)\n", out.c_str(), ro.db_path.c_str());
}

}  // namespace

void AddFitCommand(CLI::App& app) {
  auto o = std::make_shared<FitCliOptions>();
  CLI::App* cmd = app.add_subcommand("fit", "Fit variant parameters per material (the spec's \"fit\" section)");
  cmd->add_option("spec", o->spec, "Spec JSON file with a \"fit\" section")->required();
  cmd->add_option("--db", o->db, "Store for evaluations and fitted rows (default runs/<spec name>/fit.db)");
  cmd->add_option("--work", o->work, "Frame cache directory (default runs/<spec name>/frames)");
  cmd->add_option("-o,--out", o->out, "Report directory (default results/<spec name>)");
  cmd->add_flag("--keep-frames", o->keep_frames, "Keep rendered frames after measuring");
  cmd->add_option("--device", o->device, "Vulkan device name substring");
  cmd->add_option("--from-json", o->from_json,
                  "Write the report (fit.md, fit.json, plots) again from a fit.json shimmer fit wrote, rendering "
                  "nothing (the closed forms are fitted again)");
  cmd->add_option("--variant-file", o->variant_files,
                  "Also fit a user variant's GLSL file (docs/variants.md) in every fit entry (repeatable)");
  cmd->callback([o] { Run(*o); });
}

}  // namespace shimmer::cli
