// The pieces of a report, each written by its own file: the grouping and the
// per-row quantities (report.cpp), the overview across shots: leaderboard,
// classes, recommendations (report_overview.cpp), the document that
// report.md and report.html are both rendered from (report_document.cpp,
// report_markdown.cpp, report_html.cpp), the CSV of every row
// (report_csv.cpp), and the plot data and gnuplot scripts (report_plots.cpp).
#pragma once

#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "shimmer/experiments/result_store.h"

namespace shimmer::experiments::report {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One table and set of plots: the rows of a (scene, material, camera,
// derivatives) shot, sorted by label. `none` and `supersample-N` read no
// derivatives; they join every derivative group of their shot as baselines.
struct Group {
  std::string key;  // "scene / material / camera / derivatives"
  std::string scene, material, camera, derivatives;
  double alpha = kNaN;  // the material's roughness (geometric mean when anisotropic)
  std::vector<const JobResult*> rows;
  std::string Shot() const { return scene + " / " + material + " / " + camera; }
};
// Ordered by scene, then α, then material, camera and derivative source.
std::vector<Group> GroupRows(const std::vector<JobResult>& rows);

// The material's α ("ggx:0.02" → 0.02; "ggx:0.1,0.02" → √(0.1·0.02)); NaN when unreadable.
double AlphaOf(const std::string& material);
std::string RoughnessClass(double alpha);  // "α ≤ 0.02", "0.02 < α ≤ 0.1", "0.1 < α ≤ 0.3", "α > 0.3"
std::string GeometryClass(const std::string& scene);
// A row's scene traits: those its run stored with it (JobSources::scene),
// else, in a store from before they were kept, the scene loaded by name
// (a scene file that has gone since: none).
SceneTraits TraitsOf(const JobResult& row);
// Whether the group's scene is lit by a spherical Gaussian, and whether a
// primitive of it carries a normal map (TraitsOf its first row).
bool SgLitScene(const Group& group);
bool NormalMappedScene(const Group& group);

// What an engine stores per texel for a normal-map filter (seed 003's memory
// argument), by the variant's normal-map part; empty format for variants
// that read the plain normal map.
struct TexelStorage {
  std::string format;
  double bytes = 0;
};
TexelStorage NormalMapStorage(const std::string& variant);

// A metric's 95 % interval, metrics.ci95[key] = [lo, hi]; unknown when the
// store predates intervals.
struct Interval {
  double lo = kNaN, hi = kNaN;
  bool Known() const { return lo == lo && hi == hi; }
};
Interval Ci95(const JobResult& row, const char* key);

// Tokuyoshi and Kaplanyan 2019's Fig. 1 ordering in one table, from the 95 %
// intervals of the forms' relmse: the K16 non-axis-aligned form
// (`k16_non_axis`) wholly above every other form's, and the TK19
// non-axis-aligned one (`tk19_non_axis`) wholly above none (lowest, or tied
// with the lowest). False when any interval is unknown.
bool Fig1OrderingHolds(const std::vector<Interval>& relmse, std::size_t k16_non_axis, std::size_t tk19_non_axis);

// Lower is better; decision_rule.h's Separate decides which.
enum class Verdict { kBetter, kWorse, kIndistinguishable, kUnknown };

enum class Convergence { kConverged, kUnconverged, kUnchecked };
// From the rows' ShotCheck: unconverged when any says so, unchecked when none has one.
Convergence ConvergenceOf(const Group& group);
const ShotCheck* CheckOf(const Group& group);

// Quartiles by linear interpolation between order statistics (numpy's
// default); NaN for no values. NaN inputs are dropped.
struct Quartiles {
  double q1 = kNaN, median = kNaN, q3 = kNaN;
  int n = 0;
};
Quartiles QuartilesOf(std::vector<double> values);

// A row of a group against that group's `none`.
struct Sample {
  const Group* group = nullptr;
  const JobResult* row = nullptr;
  double ratio = kNaN;  // tv_err / tv_err(none); NaN without `none`
  Interval ratio_ci;    // [lo / hi(none), hi / lo(none)]: both intervals' worst cases
  double energy_bias = kNaN;
};
const JobResult* NoneOf(const Group& group);
std::vector<Sample> SamplesOf(const Group& group);

// One variant label across the tables it appears in.
struct VariantSummary {
  std::string label;
  bool supersample = false;
  bool none = false;  // the baseline (rendered, or an external sequence labelled "none")
  std::vector<Sample> samples;
  Quartiles ratio;                          // over the tables
  double ratio_lo = kNaN, ratio_hi = kNaN;  // medians of the per-table interval bounds
  double energy_share = kNaN;               // share of tables with |energy_bias| <= kEnergyTolerance (decision_rule.h)
  Quartiles energy_bias;
  std::map<std::string, Quartiles> cost_ratio;  // benchmark ratio_to_none by device
};
// Sorted by median ratio (labels without a ratio last).
std::vector<VariantSummary> Summarise(const std::vector<const Group*>& groups);
// The benchmark devices of the rows, in name order.
std::vector<std::string> BenchmarkDevices(const std::vector<const Group*>& groups);

// Cost for a group's Pareto front: the benchmark's median ms when every row
// has one from one device, else the metric render's time when every row ran
// on one device, else none (ms empty: no front across devices).
struct Costs {
  std::string source;  // what `ms` is, in words
  std::vector<double> ms, tv_err, relmse;
  std::vector<bool> front_tv_err, front_relmse;
};
Costs CostsOf(const Group& group);

// "variant name=value ...".
std::string Label(const JobResult& row);
// The metrics' region, e.g. "highlight" or "frame (highlight mask empty)".
std::string Region(const JobResult& row);
bool IsSupersample(const JobResult& row);
std::string DeviceOf(const JobResult& row);  // "unrecorded" when empty

std::string Csv(const std::vector<JobResult>& rows);

// The light sharpness of the first row whose scene has an SG light
// (TraitsOf); nullopt when no row's does.
std::optional<double> SgSharpnessOf(const std::vector<JobResult>& rows);

struct PlotFile {
  std::string name, text;
  bool script = false;  // a gnuplot script to run
};
std::vector<PlotFile> Plots(const Group& group);
// Variants (leaderboard order) x tables: log10 of the tv_err ratio to `none`,
// crossed where |energy_bias| > kEnergyTolerance (decision_rule.h). Files "heatmap.*".
std::vector<PlotFile> Heatmap(const std::vector<VariantSummary>& variants, const std::vector<const Group*>& groups);

}  // namespace shimmer::experiments::report
