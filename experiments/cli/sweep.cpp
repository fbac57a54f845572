// `shimmer sweep`: one variant parameter over a range, everything else fixed;
// prints a table, and writes it as CSV with a gnuplot script and plot.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "commands.h"
#include "job.h"
#include "output_files.h"
#include "runner.h"
#include "spec.h"

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
  nlohmann::json spec = {
      {"name", "sweep"},
      {"scenes", {o.scene}},
      {"materials", {o.material}},
      {"cameras", {o.camera}},
      {"variants",
       {{{"name", o.variant},
         {"params", {{*name, {{"from", from}, {"to", to}, {"steps", steps}, {"scale", o.log ? "log" : "linear"}}}}}}}},
      {"derivatives", {o.derivatives}},
      {"size", o.size},
      {"frames", o.frames},
      {"fps", o.fps},
      {"reference", {{"spp", o.reference_spp}}},
      {"metrics", {{"highlight_mask", false}}}};
  experiments::SpecResult r = experiments::ParseSpec(spec.dump(), "sweep");
  if (!r.ok()) throw UsageError(r.error);
  return r.spec;
}

void Run(const SweepOptions& o) {
  std::string name;
  const experiments::Spec spec = SweepSpec(o, &name);
  experiments::RunOptions ro;
  ro.work_dir = o.work;
  ro.device = o.device;
  std::filesystem::create_directories(o.work);
  std::ostringstream csv;
  csv << name << ",tv_ratio,tv_err,energy_bias,relmse,flicker_index,ms_per_frame\n";
  std::printf("%12s %10s %10s %12s %10s %13s %12s\n", name.c_str(), "tv_ratio", "tv_err", "energy_bias", "relmse",
              "flicker_index", "ms/frame");
  for (const experiments::Job& job : experiments::ExpandJobs(spec)) {
    experiments::Measured m = experiments::MeasureJob(job, ro);
    if (!m.error.empty()) throw std::runtime_error(m.error);
    const auto& j = m.result.metrics;
    const double fi = experiments::FlickerIndex(j);
    const double tv_ratio = experiments::Metric(j, "tv_ratio"), tv_err = experiments::Metric(j, "tv_err");
    const double bias = experiments::Metric(j, "energy_bias"), relmse = experiments::Metric(j, "relmse");
    const double v = job.params.at(name);
    std::printf("%12.5g %10.4g %10.4g %12.4g %10.4g %13.4g %12.3f\n", v, tv_ratio, tv_err, bias, relmse, fi,
                m.result.gpu_ms_per_frame);
    std::fflush(stdout);
    csv << v << "," << tv_ratio << "," << tv_err << "," << bias << "," << relmse << "," << fi << ","
        << m.result.gpu_ms_per_frame << "\n";
  }
  if (o.csv.empty()) return;
  const std::filesystem::path path(o.csv);
  if (std::string e = experiments::WriteFileAtomic(path, csv.str()); !e.empty()) throw std::runtime_error(e);
  // The plot script sits beside the data so users can restyle it.
  std::filesystem::path gp = path, svg = path;
  gp.replace_extension(".gp");
  svg.replace_extension(".svg");
  std::ostringstream script;
  script << "set terminal svg size 720,420 dynamic\nset output '" << svg.filename().string() << "'\n"
         << "set datafile separator ','\nset key autotitle columnhead\nset xlabel '" << name << "'\n"
         << (o.log ? "set logscale x\n" : "") << "set ylabel 'tv_ratio, flicker_index'\nset y2label 'energy_bias'\n"
         << "set y2tics\nset ytics nomirror\n"
         << "plot '" << path.filename().string() << "' using 1:2 with linespoints, '' using 1:6 with linespoints, "
         << "'' using 1:4 axes x1y2 with linespoints\n";
  if (std::string e = experiments::WriteFileAtomic(gp, script.str()); !e.empty()) throw std::runtime_error(e);
  std::vector<std::string> warnings;
  experiments::RunGnuplot(path.parent_path(), {gp.filename().string()}, &warnings);
  for (const std::string& w : warnings) std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
  std::printf("wrote %s, %s, %s\n", path.c_str(), gp.c_str(), svg.c_str());
}

}  // namespace

void AddSweepCommand(CLI::App& app) {
  auto o = std::make_shared<SweepOptions>();
  CLI::App* cmd = app.add_subcommand("sweep", "Sweep one variant parameter, everything else fixed; print a table");
  cmd->add_option("--scene", o->scene)->capture_default_str();
  cmd->add_option("--material", o->material)->capture_default_str();
  cmd->add_option("--camera", o->camera)->capture_default_str();
  cmd->add_option("--variant", o->variant)->capture_default_str();
  cmd->add_option("--param", o->param, "name=from:to:steps, e.g. fp_max=0.05:2:12")->required();
  cmd->add_flag("--log", o->log, "Logarithmic steps");
  cmd->add_option("--derivatives", o->derivatives, "quad, quad-coarse or analytic")->capture_default_str();
  cmd->add_option("--size", o->size, "W H")->expected(2);
  cmd->add_option("--frames", o->frames)->capture_default_str();
  cmd->add_option("--fps", o->fps)->capture_default_str();
  cmd->add_option("--reference-spp", o->reference_spp, "N: N x N samples per pixel")->capture_default_str();
  cmd->add_option("--csv", o->csv, "Also write the table as CSV, with a gnuplot script and SVG beside it");
  cmd->add_option("--work", o->work, "Frame cache")->capture_default_str();
  cmd->add_option("--device", o->device, "Vulkan device name substring");
  cmd->callback([o] { Run(*o); });
}

}  // namespace shimmer::cli
