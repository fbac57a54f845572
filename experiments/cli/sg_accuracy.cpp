// `shimmer sg-accuracy`: how close seed 004's SG-warp and ASG-warp
// approximations come to the exact GGX response to an SG light, per
// roughness and view angle (shimmer/experiments/sg_accuracy.h); CPU only.
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "shimmer/experiments/sg_accuracy.h"

namespace shimmer::cli {

namespace {

struct SgAccuracyCliOptions {
  experiments::SgAccuracyOptions measure;
  std::string out;
  bool json = false;
};

const FieldFlags kFlags = {
    {"alphas", "--alpha"}, {"views_deg", "--view"}, {"sharpness", "--sharpness"}, {"samples", "--samples"}};

void Run(const SgAccuracyCliOptions& o) {
  // Bad input and an unusable output directory are found before the work.
  Check(experiments::ValidateSgAccuracyOptions(o.measure), kFlags);
  if (!o.out.empty()) RequireCreatableDirectory("-o", o.out);
  const experiments::SgAccuracyTable table = Take(experiments::MeasureSgAccuracy(o.measure), kFlags);
  if (o.json) {
    std::cout << experiments::SgAccuracyJson(table).dump() << "\n";
  } else {
    std::printf(
        "Energy error, sum(approx) / sum(exact) - 1 over %d lights (SG warp / ASG warp), light sharpness %g:\n\n",
        experiments::kSgAccuracyGridSide * experiments::kSgAccuracyGridSide, o.measure.sharpness);
    std::printf("%s\n", experiments::SgMarkdownTable(experiments::SgEnergyTable(table)).c_str());
    std::printf("relmse, mean of (approx - exact)^2 / (exact^2 + 0.01) (SG warp / ASG warp):\n\n");
    std::printf("%s\n", experiments::SgMarkdownTable(experiments::SgRelmseTable(table)).c_str());
    std::printf(
        "Reference: %d x %d MIS estimates per light; relative standard error of a cell's sum at most %.2g %%.\n",
        o.measure.samples, o.measure.samples, 100 * table.MaxRefRelStderr());
  }
  std::fflush(stdout);
  if (o.out.empty()) return;
  std::vector<std::string> warnings;
  Check(experiments::WriteSgAccuracy(table, o.out, &warnings));
  for (const std::string& w : warnings) std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
  const std::string wrote = "wrote " + o.out + "/sg_accuracy.md, .csv, .dat, .gp" + (warnings.empty() ? ", .svg" : "");
  // --json keeps stdout one JSON object.
  if (o.json)
    std::fprintf(stderr, "shimmer: %s\n", wrote.c_str());
  else
    std::printf("%s\n", wrote.c_str());
}

}  // namespace

void AddSgAccuracyCommand(CLI::App& app) {
  auto o = std::make_shared<SgAccuracyCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sg-accuracy", "Seed 004's SG / ASG warp against the exact GGX response to an SG light (CPU tables)");
  cmd->add_option("--alpha", o->measure.alphas, "GGX roughness values, in [1e-4, 1]")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--view", o->measure.views_deg, "View angles from the normal in degrees, in [0, 90)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--sharpness", o->measure.sharpness, "The SG light's sharpness lambda, in (0, 1e6]")
      ->capture_default_str();
  cmd->add_option("--samples", o->measure.samples, "Reference: N x N MIS estimates per light, N in 4..512")
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "Print one JSON object instead of the tables");
  cmd->add_option("-o,--output", o->out,
                  "Also write sg_accuracy.md, .csv, .dat, .gp and .svg into this directory (created)");
  cmd->callback([o] { Run(*o); });
}

}  // namespace shimmer::cli
