#include "shimmer/experiments/report.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>

#include "decision_rule.h"
#include "report_document.h"
#include "report_parts.h"
#include "shimmer/core/gnuplot.h"
#include "shimmer/experiments/output_files.h"
#include "shimmer/experiments/sg_accuracy.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"

namespace shimmer::experiments {

namespace report {

std::string Label(const JobResult& r) {
  // Every table, plot and summary says which rows shimmer did not render.
  if (r.job.external) return r.job.variant + " (external)";
  std::string label = r.job.variant;
  for (const auto& [k, v] : r.job.params) {
    std::ostringstream s;
    s << " " << k << "=" << v;
    label += s.str();
  }
  return label;
}

std::string Region(const JobResult& r) { return r.metrics.value("region", std::string("frame")); }

bool IsSupersample(const JobResult& r) {
  if (r.job.external) return false;
  auto name = shading::ParseVariantName(r.job.variant);
  return name && name->kind == shading::VariantName::Kind::kSupersample;
}

std::string DeviceOf(const JobResult& r) { return r.device.empty() ? "unrecorded" : r.device; }

double AlphaOf(const std::string& material) {
  auto m = scene::ParseMaterial(material, shading::MaterialDesc{});
  if (!m || m->alpha.x <= 0 || m->alpha.y <= 0) return kNaN;
  return std::sqrt(m->alpha.x * m->alpha.y);
}

std::string RoughnessClass(double alpha) {
  if (std::isnan(alpha)) return "α unknown";
  if (alpha <= 0.02) return "α ≤ 0.02";
  if (alpha <= 0.1) return "0.02 < α ≤ 0.1";
  if (alpha <= 0.3) return "0.1 < α ≤ 0.3";
  return "α > 0.3";
}

std::string GeometryClass(const std::string& scene) {
  if (scene == "sphere" || scene == "sphere-field") return "small curved";
  if (scene == "wires") return "thin";
  if (scene == "bumpy-plane") return "flat with normal detail";
  return "other";
}

Interval Ci95(const JobResult& row, const char* key) {
  const auto ci = MetricCi95(row.metrics, key);
  if (!ci) return {};
  return {ci->first, ci->second};
}

const ShotCheck* CheckOf(const Group& group) {
  const ShotCheck* check = nullptr;
  for (const JobResult* r : group.rows)
    if (r->shot && (!check || !r->shot->converged)) check = &*r->shot;
  return check;
}

Convergence ConvergenceOf(const Group& group) {
  const ShotCheck* check = CheckOf(group);
  if (!check) return Convergence::kUnchecked;
  return check->converged ? Convergence::kConverged : Convergence::kUnconverged;
}

Quartiles QuartilesOf(std::vector<double> values) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return std::isnan(v); }), values.end());
  Quartiles q;
  q.n = int(values.size());
  if (values.empty()) return q;
  std::sort(values.begin(), values.end());
  auto at = [&](double p) {
    const double pos = p * double(values.size() - 1);
    const std::size_t i = std::size_t(std::floor(pos));
    const double t = pos - double(i);
    return i + 1 < values.size() ? values[i] + t * (values[i + 1] - values[i]) : values[i];
  };
  q.q1 = at(0.25), q.median = at(0.5), q.q3 = at(0.75);
  return q;
}

const JobResult* NoneOf(const Group& group) {
  // A shot shimmer renders has its own `none`; an engine's shot can bring one
  // as an external sequence labelled "none".
  const JobResult* external = nullptr;
  for (const JobResult* r : group.rows)
    if (r->job.variant == "none") {
      if (!r->job.external) return r;
      external = r;
    }
  return external;
}

std::vector<Sample> SamplesOf(const Group& group) {
  const JobResult* none = NoneOf(group);
  const double none_err = none ? Metric(none->metrics, "tv_err") : kNaN;
  const Interval none_ci = none ? Ci95(*none, "tv_err") : Interval{};
  std::vector<Sample> out;
  for (const JobResult* r : group.rows) {
    Sample s;
    s.group = &group, s.row = r;
    const double err = Metric(r->metrics, "tv_err");
    if (none_err > 0) s.ratio = err / none_err;
    const Interval ci = Ci95(*r, "tv_err");
    if (ci.Known() && none_ci.Known() && none_ci.lo > 0) s.ratio_ci = {ci.lo / none_ci.hi, ci.hi / none_ci.lo};
    s.energy_bias = Metric(r->metrics, "energy_bias");
    out.push_back(s);
  }
  return out;
}

std::vector<Group> GroupRows(const std::vector<JobResult>& rows) {
  std::map<std::string, Group> groups;
  std::map<std::string, std::set<std::string>> sources_of_shot;
  auto shot = [](const JobResult& r) { return r.job.scene + " / " + r.job.material + " / " + r.job.camera; };
  // External frames read no derivatives of shimmer's: like `none`, they join
  // every rendered derivative group of their shot, or one of their own.
  for (const JobResult& r : rows)
    if (!r.job.external) sources_of_shot[shot(r)].insert(r.job.derivatives);
  for (const JobResult& r : rows)
    if (r.job.external && !sources_of_shot.count(shot(r))) sources_of_shot[shot(r)].insert(kExternalDerivatives);
  auto add = [&](const JobResult& r, const std::string& source) {
    Group& g = groups[shot(r) + " / " + source];
    if (g.rows.empty()) {
      g.key = shot(r) + " / " + source;
      g.scene = r.job.scene, g.material = r.job.material, g.camera = r.job.camera, g.derivatives = source;
      g.alpha = AlphaOf(r.job.material);
    }
    g.rows.push_back(&r);
  };
  for (const JobResult& r : rows) {
    if (!r.job.external && ReadsDerivatives(r.job.variant)) {
      add(r, r.job.derivatives);
      continue;
    }
    for (const std::string& source : sources_of_shot[shot(r)]) add(r, source);
  }
  std::vector<Group> out;
  for (auto& [key, group] : groups) {
    std::sort(group.rows.begin(), group.rows.end(),
              [](const JobResult* a, const JobResult* b) { return Label(*a) < Label(*b); });
    out.push_back(std::move(group));
  }
  // NaN α (unreadable material) sorts after every number.
  auto order = [](const Group& g) {
    return std::make_tuple(g.scene, std::isnan(g.alpha), std::isnan(g.alpha) ? 0.0 : g.alpha, g.material, g.camera,
                           g.derivatives);
  };
  std::stable_sort(out.begin(), out.end(), [&](const Group& a, const Group& b) { return order(a) < order(b); });
  return out;
}

Costs CostsOf(const Group& group) {
  Costs c;
  std::set<std::string> bench_devices, render_devices;
  bool all_bench = true;
  // An external sequence without a cost has no time at all: it sits off the
  // front instead of taking the front from every other row.
  auto timed = [](const JobResult* r) { return !r->job.external || r->cost.has_value(); };
  for (const JobResult* r : group.rows) {
    if (timed(r)) {
      if (r->cost)
        bench_devices.insert(r->cost->device);
      else
        all_bench = false;
      render_devices.insert(DeviceOf(*r));
    }
    c.tv_err.push_back(Metric(r->metrics, "tv_err"));
    c.relmse.push_back(Metric(r->metrics, "relmse"));
  }
  if (all_bench && bench_devices.size() == 1) {
    c.source = "benchmark median GPU ms per frame on " + *bench_devices.begin();
    for (const JobResult* r : group.rows) c.ms.push_back(timed(r) ? r->cost->median_ms : kNaN);
  } else if (render_devices.size() == 1) {
    c.source = "the metric render's GPU ms per frame on " + *render_devices.begin() +
               " (no benchmark for every row: small renders, noisy)";
    for (const JobResult* r : group.rows) c.ms.push_back(timed(r) ? r->gpu_ms_per_frame : kNaN);
  } else {
    c.source = "none: the rows ran on several devices, whose times are not comparable";
  }
  c.front_tv_err.assign(group.rows.size(), false);
  c.front_relmse.assign(group.rows.size(), false);
  if (c.ms.empty()) return c;
  for (int i : ParetoFront(c.ms, c.tv_err)) c.front_tv_err[i] = true;
  for (int i : ParetoFront(c.ms, c.relmse)) c.front_relmse[i] = true;
  return c;
}

SceneTraits TraitsOf(const JobResult& row) {
  if (const JobSources sources = JobSources::FromJson(row.sources); sources.scene.known) return sources.scene;
  const auto scene = scene::LoadScene(row.job.scene);
  return scene ? TraitsOfScene(*scene) : SceneTraits{};
}

std::optional<double> SgSharpnessOf(const std::vector<JobResult>& rows) {
  std::set<std::string> seen;
  for (const JobResult& r : rows) {
    if (!seen.insert(r.job.scene).second) continue;
    if (const SceneTraits traits = TraitsOf(r); traits.sg_light) return traits.sg_sharpness;
  }
  return std::nullopt;
}

bool SgLitScene(const Group& group) { return !group.rows.empty() && TraitsOf(*group.rows.front()).sg_light; }

bool NormalMappedScene(const Group& group) {
  return !group.rows.empty() && TraitsOf(*group.rows.front()).normal_maps;
}

// Formats as engines ship them: block-compressed where the data survives it
// (BC5 two-channel normals, BC4 one-channel gloss), uncompressed 8-bit where
// the vector's length is the signal (seed 003: compression "will still mess
// with vector length"), 16-bit floats where the moments need the precision
// (seed 003 on LEAN: "8-bit textures only make sense if absolutely needed").
TexelStorage NormalMapStorage(const std::string& variant) {
  const std::size_t plus = variant.find('+');
  const std::string nm = plus == std::string::npos ? variant : variant.substr(plus + 1);
  if (nm == "toksvig" || nm == "toksvig-bp" || nm == "vmf" || nm == "unity-hdrp-nm")
    return {"unnormalised normal, RGBA8", 4};
  if (nm == "toksvig-map") return {"normal BC5 + Toksvig factor BC4", 1.5};
  if (nm == "lean") return {"B and M: two RGBA16F textures", 16};
  if (nm == "clean") return {"B and M_z: one RGBA16F texture", 8};
  return {"normal BC5", 1};
}

}  // namespace report

std::vector<int> ParetoFront(const std::vector<double>& cost, const std::vector<double>& error) {
  std::vector<int> front;
  for (std::size_t i = 0; i < cost.size(); ++i) {
    if (std::isnan(cost[i])) continue;  // untimed: neither on the front nor dominating
    bool dominated = false;
    for (std::size_t j = 0; j < cost.size() && !dominated; ++j)
      dominated = j != i && cost[j] <= cost[i] && error[j] <= error[i] && (cost[j] < cost[i] || error[j] < error[i]);
    if (!dominated) front.push_back(int(i));
  }
  return front;
}

std::vector<JobResult> CurrentRows(std::vector<JobResult> rows, const std::set<std::string>& current,
                                   std::string* note) {
  auto is_current = [&](const JobResult& r) { return current.count(r.id) > 0; };
  const std::size_t kept = std::size_t(std::count_if(rows.begin(), rows.end(), is_current));
  if (kept == rows.size()) return rows;
  if (kept == 0) {
    if (note)
      *note = "no row of the store is one this shimmer would make (code or content changed since it ran): the "
              "report shows all " +
              std::to_string(rows.size()) + "; run the spec again to bring them up to date";
    return rows;
  }
  const std::size_t before = rows.size();
  std::erase_if(rows, [&](const JobResult& r) { return !is_current(r); });
  if (note)
    *note = "the store holds " + std::to_string(before - rows.size()) +
            " rows made by other code or content than this shimmer's: the report shows the " +
            std::to_string(rows.size()) + " current ones and leaves those out (shimmer prune removes them)";
  return rows;
}

Status WriteReport(const std::vector<JobResult>& rows, const std::string& title, const std::string& out_dir,
                   std::vector<std::string>* warnings, const ShotVideoWriter& video,
                   const std::vector<JointFit>& engine_fits) {
  if (rows.empty()) return Status::Failure("the results store has no finished jobs");
  auto staged = StagedDirectory::Create(out_dir);
  if (!staged) return staged.failure();
  StagedDirectory& dir = **staged;
  if (Status s = dir.Write("report.csv", report::Csv(rows)); !s) return s;
  const std::vector<report::Group> groups = report::GroupRows(rows);
  // Seed 004's approximations on their own, for stores with SG-lit shots only:
  // every other report stays as it was.
  std::optional<SgAccuracyTable> sg;
  if (const std::optional<double> sharpness = report::SgSharpnessOf(rows)) {
    SgAccuracyOptions options;
    options.sharpness = *sharpness;
    auto measured = MeasureSgAccuracy(options);
    if (measured)
      sg = std::move(*measured);
    else if (warnings)
      warnings->push_back("the report has no section \"" + std::string(report::kSgAccuracyHeading) +
                          "\": " + measured.error());
  }
  std::set<std::string> videos;  // group keys with a grid video
  if (video)
    for (const report::Group& group : groups) {
      std::vector<const JobResult*> ordered = group.rows;
      std::stable_partition(ordered.begin(), ordered.end(), [](const JobResult* r) { return r->job.variant == "none"; });
      const std::filesystem::path file = dir.staging() / (Slug(group.key) + kVideoSuffix);
      if (Status s = video(ordered, file); !s) return dir.Unstaged(Prefixed("video of " + group.key, s.failure()));
      videos.insert(group.key);
    }
  const report::Document doc = report::BuildDocument(groups, title, rows.size(), sg ? &*sg : nullptr, &videos, engine_fits);

  std::vector<report::PlotFile> files;
  if (sg) {
    const std::string stem = report::kSgAccuracyStem;
    files.push_back({stem + ".csv", SgAccuracyCsv(*sg)});
    files.push_back({stem + ".dat", SgAccuracyPlotData(*sg)});
    files.push_back({stem + ".gp", SgAccuracyPlotScript(*sg, stem), true});
  }
  for (const report::Group& group : groups)
    for (report::PlotFile& f : report::Plots(group)) files.push_back(std::move(f));
  std::vector<const report::Group*> included;
  for (const report::Group& g : groups)
    if (report::ConvergenceOf(g) != report::Convergence::kUnconverged) included.push_back(&g);
  for (report::PlotFile& f : report::Heatmap(report::Summarise(included), included)) files.push_back(std::move(f));
  files.push_back({"cells.csv", report::CellsCsv(report::AnswerCells(included))});
  std::vector<std::string> scripts;
  for (const report::PlotFile& f : files) {
    if (Status s = dir.Write(f.name, f.text); !s) return s;
    if (f.script) scripts.push_back(f.name);
  }
  for (const std::string& script : scripts)
    if (Status s = RunGnuplot(dir.staging(), script); !s) {
      // gnuplot missing or failing costs the plots; a plot cut short (a full disk) fails the report.
      if (s.code() == ErrorCode::kIo) return dir.Unstaged(s.failure());
      if (warnings) warnings->push_back(s.error());
    }
  const std::string html = report::ToHtml(doc, [&](const std::string& file) -> std::optional<std::string> {
    std::ifstream in(dir.staging() / file, std::ios::binary);
    if (!in) return std::nullopt;
    return std::string((std::istreambuf_iterator<char>(in)), {});
  });
  if (Status s = dir.Write("report.html", html); !s) return s;
  if (Status s = dir.Write("report.md", report::ToMarkdown(doc)); !s) return s;
  return dir.Commit("report.md");
}

}  // namespace shimmer::experiments
