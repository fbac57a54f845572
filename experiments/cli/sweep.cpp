// `shimmer sweep`: one variant parameter over a range, everything else fixed;
// prints a table, and writes it as CSV with a gnuplot script and plot.
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "commands.h"
#include "shimmer/core/gnuplot.h"
#include "shimmer/experiments/csv.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/output_files.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/experiments/spec.h"

namespace shimmer::cli {

namespace {

struct SweepOptions {
  std::string scene = "sphere-field", material = "ggx:0.02", camera = "orbit", variant = "k16-beckmann-rect";
  std::string param;  // name=from:to:steps
  bool log = false;
  std::string derivatives = "quad";
  std::vector<int> size{96, 96};
  int frames = 16;
  double fps = 30;
  int reference_spp = 4;
  std::string csv;
  std::string work = "runs/sweep";
  std::string device;
  std::string variant_file;
};

// Builds a one-variant spec and lets the spec parser validate it, so a sweep
// accepts exactly what a spec file would.
experiments::Spec SweepSpec(const SweepOptions& o, std::string* name) {
  const auto eq = o.param.find('=');
  if (eq == std::string::npos) throw UsageError("--param expects name=from:to:steps, got '" + o.param + "'");
  *name = o.param.substr(0, eq);
  double from = 0, to = 0;
  int steps = 0;
  char tail = 0;
  if (std::sscanf(o.param.c_str() + eq + 1, "%lf:%lf:%d%c", &from, &to, &steps, &tail) != 3)
    throw UsageError("--param expects name=from:to:steps, got '" + o.param + "'");
  nlohmann::json variant = {{"name", o.variant},
                             {"params",
                              {{*name, {{"from", from}, {"to", to}, {"steps", steps}, {"scale", o.log ? "log" : "linear"}}}}}};
  if (!o.variant_file.empty()) {
    variant["file"] = o.variant_file;
    variant["name"] = UserVariantName(o.variant_file);
  }
  nlohmann::json spec = {
      {"name", "sweep"},
      {"scenes", {o.scene}},
      {"materials", {o.material}},
      {"cameras", {o.camera}},
      {"variants", {variant}},
      {"derivatives", {o.derivatives}},
      {"size", o.size},
      {"frames", o.frames},
      {"fps", o.fps},
      {"reference", {{"spp", o.reference_spp}}}};
  auto parsed = experiments::ParseSpec(spec.dump(), "sweep");
  if (parsed) return *parsed;
  // "sweep:1: size: must be ..." names the spec's key; the user typed a flag.
  // The line is there only when the key is ("fp_max.steps" is not).
  std::string message = parsed.error();
  if (message.rfind("sweep:", 0) == 0) message.erase(0, 6);
  if (!message.empty() && std::isdigit(static_cast<unsigned char>(message.front()))) {
    while (!message.empty() && std::isdigit(static_cast<unsigned char>(message.front()))) message.erase(0, 1);
    if (!message.empty() && message.front() == ':') message.erase(0, 1);
  }
  if (!message.empty() && message.front() == ' ') message.erase(0, 1);
  const FieldFlags keys = {{*name + ".steps:", "--param " + o.param + ": steps"},
                           {*name + ".from:", "--param " + o.param + ": from"},
                           {*name + ".to:", "--param " + o.param + ": to"},
                           {"size:", "--size:"},
                           {"frames:", "--frames:"},
                           {"fps:", "--fps:"},
                           {"spp:", "--reference-spp:"},
                           {"derivatives:", "--derivatives:"},
                           {"file:", "--variant-file:"},
                           {o.variant + ":", "--variant " + o.variant + ":"},
                           {o.camera + ":", "--camera " + o.camera + ":"},
                           {o.material + ":", "--material " + o.material + ":"},
                           {o.scene + ":", "--scene " + o.scene + ":"},
                           {*name + ":", "--param " + *name + ":"}};
  throw CommandError(WithFlagNames(Error{parsed.code(), message}, keys));
}

void Run(const SweepOptions& o) {
  std::string name;
  const experiments::Spec spec = SweepSpec(o, &name);
  // Found before any rendering: the table would be lost after the work.
  if (!o.csv.empty()) RequireParentDirectory("--csv", o.csv);
  experiments::RunOptions ro;
  ro.work_dir = o.work;
  ro.device = o.device;
  // A frame cache this sweep made goes with a sweep that fails; one that was there stays.
  NewDirectories dirs(/*with_contents=*/true);
  dirs.Create("--work " + o.work, o.work);
  experiments::CsvTable csv({name, "tv_ratio", "tv_err", "energy_bias", "relmse", "flicker_index", "ms_per_frame"});
  bool header = false;
  for (const experiments::Job& job : experiments::ExpandJobs(spec)) {
    const experiments::JobResult result = Take(experiments::MeasureJob(job, ro));
    const auto& j = result.metrics;
    if (!header) {
      // As `run` does: the spec's highlight mask, where the reference has highlights.
      std::printf("region: %s\n", j.value("region", std::string("frame")).c_str());
      std::printf("%12s %10s %10s %12s %10s %13s %12s\n", name.c_str(), "tv_ratio", "tv_err", "energy_bias", "relmse",
                  "flicker_index", "ms/frame");
      header = true;
    }
    const double fi = experiments::FlickerIndex(j);
    const double tv_ratio = experiments::Metric(j, "tv_ratio"), tv_err = experiments::Metric(j, "tv_err");
    const double bias = experiments::Metric(j, "energy_bias"), relmse = experiments::Metric(j, "relmse");
    const double v = job.params.at(name);
    std::printf("%12.5g %10.4g %10.4g %12.4g %10.4g %13.4g %12.3f\n", v, tv_ratio, tv_err, bias, relmse, fi,
                result.gpu_ms_per_frame);
    std::fflush(stdout);
    csv.AddRow({experiments::CsvNumber(v), experiments::CsvNumber(tv_ratio), experiments::CsvNumber(tv_err),
                experiments::CsvNumber(bias), experiments::CsvNumber(relmse), experiments::CsvNumber(fi),
                experiments::CsvNumber(result.gpu_ms_per_frame)});
  }
  if (o.csv.empty()) return dirs.Keep();
  const std::filesystem::path path(o.csv);
  // The table, its script and its plot appear together or not at all.
  auto staged = Take(StagedDirectory::Create(path.parent_path()));
  auto check = [&staged](const Status& s) {
    if (!s) throw CommandError(staged->Unstaged(s.failure()));
  };
  check(staged->Write(path.filename().string(), csv.Text()));
  // The plot script sits beside the data so users can restyle it.
  std::filesystem::path gp = path, svg = path;
  gp.replace_extension(".gp");
  svg.replace_extension(".svg");
  std::ostringstream s;
  s << "set terminal svg size 720,420 dynamic noenhanced\nset output '" << svg.filename().string() << "'\n"
    << "set datafile separator ','\nset key autotitle columnhead\nset xlabel '" << name << "'\n"
    << (o.log ? "set logscale x\n" : "") << "set ylabel 'tv_ratio, flicker_index'\nset y2label 'energy_bias'\n"
    << "set y2tics\nset ytics nomirror\n"
    << "plot '" << path.filename().string() << "' using 1:2 with linespoints, '' using 1:6 with linespoints, "
    << "'' using 1:4 axes x1y2 with linespoints\n";
  auto plotted = WritePlot(staged->staging(), gp.filename().string(), svg.filename().string(), s.str());
  if (!plotted) throw CommandError(staged->Unstaged(plotted.failure()));
  const std::optional<std::string> warning = *plotted;
  check(staged->Commit(path.filename().string()));
  dirs.Keep();
  if (warning) {
    const std::string text = staged->Unstaged(Error{ErrorCode::kInternal, *warning}).message;
    std::fprintf(stderr, "shimmer: warning: %s\n", text.c_str());
  }
  std::printf("wrote %s, %s%s\n", path.c_str(), gp.c_str(), warning ? "" : (", " + svg.string()).c_str());
}

}  // namespace

void AddSweepCommand(CLI::App& app) {
  auto o = std::make_shared<SweepOptions>();
  CLI::App* cmd = app.add_subcommand("sweep", "Sweep one variant parameter, everything else fixed; print a table");
  cmd->add_option("--scene", o->scene, "Built-in scene name or JSON scene file")->capture_default_str();
  cmd->add_option("--material", o->material, "Material spec NDF:ALPHA[,...]")->capture_default_str();
  cmd->add_option("--camera", o->camera, "Camera path")->capture_default_str();
  cmd->add_option("--variant", o->variant, "Filter variant whose parameter is swept")->capture_default_str();
  cmd->add_option("--variant-file", o->variant_file,
                  "A user variant's GLSL file instead (docs/variants.md); --param sweeps one it declares");
  cmd->add_option("--param", o->param, "name=from:to:steps, e.g. fp_max=0.05:2:12")->required();
  cmd->add_flag("--log", o->log, "Logarithmic steps");
  cmd->add_option("--derivatives", o->derivatives, "quad, quad-coarse or analytic")->capture_default_str();
  cmd->add_option("--size", o->size, "Width and height in pixels")->expected(2)->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames per render (>= 2)")->capture_default_str();
  cmd->add_option("--fps", o->fps, "Frames per second (camera time step)")->capture_default_str();
  cmd->add_option("--reference-spp", o->reference_spp, "N: N x N samples per pixel")->capture_default_str();
  cmd->add_option("--csv", o->csv, "Also write the table as CSV, with a gnuplot script and SVG beside it");
  cmd->add_option("--work", o->work, "Frame cache")->capture_default_str();
  cmd->add_option("--device", o->device, "Vulkan device name substring");
  cmd->callback([o, cmd] {
    RequireOneFilter(*cmd, o->variant, o->variant_file);
    Run(*o);
  });
}

}  // namespace shimmer::cli
