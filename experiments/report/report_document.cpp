// What the report says, in order: the overview across shots (leaderboard,
// heatmap, recommendations, shots left out), the per-shot tables, the method.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "report_document.h"
#include "shimmer/experiments/output_files.h"
#include "shimmer/experiments/report.h"

namespace shimmer::experiments::report {

std::string Fmt(double v, const char* f) { return std::isnan(v) ? "n/a" : FormatNumber(v, f); }

std::string WithInterval(double v, Interval ci, const char* f) {
  if (std::isnan(v)) return "n/a";
  std::string text = FormatNumber(v, f);
  if (ci.Known()) text += " [" + FormatNumber(ci.lo, f) + ", " + FormatNumber(ci.hi, f) + "]";
  return text;
}

std::string Percent(double share) { return std::isnan(share) ? "n/a" : FormatNumber(100 * share, "%.0f") + " %"; }

std::string Code(const std::string& s) { return "`" + s + "`"; }

std::string Join(const std::vector<std::string>& items, const std::string& sep) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : sep) + s;
  return out;
}

std::string Ratio(const Quartiles& q) {
  if (q.n == 0) return "n/a";
  return Fmt(q.median, "%.3g") + " (IQR " + Fmt(q.q1, "%.3g") + "–" + Fmt(q.q3, "%.3g") + ")";
}

std::string Bounds(double lo, double hi) {
  return std::isnan(lo) || std::isnan(hi) ? "n/a" : "[" + Fmt(lo, "%.3g") + ", " + Fmt(hi, "%.3g") + "]";
}

namespace {

std::string CheckNumbers(const ShotCheck& c) {
  return "spp " + std::to_string(c.spp) + " vs " + std::to_string(c.check_spp) + " per axis" +
         (c.frame_stride > 1 ? " on 1 in " + std::to_string(c.frame_stride) + " frames" : "") + "; changes: tv_ref " +
         Fmt(c.d_tv_ref, "%.3g") + " (tolerance " + Fmt(c.tol_tv, "%.3g") + "), energy_bias " +
         Fmt(c.d_energy_bias, "%.3g") + " (tolerance " + Fmt(c.tol_energy, "%.3g") + "), tv_err " +
         Fmt(c.d_tv_err, "%.3g") + " (tolerance " + Fmt(c.tol_tv, "%.3g") + ")" +
         (c.sparkle_count > 0 || c.sparkle_count_check > 0
              ? ", sparkles per frame " + Fmt(c.sparkle_count, "%.4g") + " vs " + Fmt(c.sparkle_count_check, "%.4g") +
                    ": " + Fmt(c.d_sparkle_count, "%.3g") + " (tolerance " + Fmt(c.tol_tv, "%.3g") + ")"
              : "") +
         (c.unconverged_pixels ? "; " + std::to_string(c.unconverged_pixels) + " pixel-frames above tolerance" : "");
}

void Overview(Document& doc, const std::vector<const Group*>& included, const std::vector<const Group*>& unconverged,
              const std::vector<const Group*>& unchecked, const std::vector<CellAnswer>& cells,
              const std::vector<JointFit>& engine_fits) {
  std::set<std::string> shots;
  for (const Group* g : included) shots.insert(g->Shot());
  const std::vector<std::string> devices = BenchmarkDevices(included);

  doc.Heading(2, kOverviewHeading);
  doc.Paragraph(std::to_string(included.size()) + " tables (" + std::to_string(shots.size()) +
                " shots × derivative sources) enter the answer; unconverged shots are left out (listed below). "
                "Ratios are a variant's value over `none`'s in the same table. Joint error: `relmse`, the mean over "
                "frames of the relative squared error against the reference frame (unitless). Cost: benchmark time "
                "over `none`'s in the same batch" +
                (devices.empty() ? std::string(" (no benchmark in this store: n/a)")
                                 : ", on " + Join(devices, " and ") +
                                       (CpuDevice(devices) ? " (CPU time: lavapipe runs the shaders on the CPU)" : "")) +
                ".");
  CellDetails(doc, cells);
  ClassLeaderboards(doc, included);

  doc.Heading(3, kHeatmapHeading);
  doc.Paragraph(
      "log10 of the `tv_err` ratio to `none` per variant and table: blue is steadier than `none`, red less "
      "steady; × marks |energy_bias| > 0.10.");
  doc.Figures({"heatmap.svg"}, {"variants × shots: log10 tv_err ratio to none"});

  ReferenceNoiseSection(doc, included);

  doc.Heading(3, kExcludedHeading);
  std::vector<std::string> items;
  std::set<std::string> listed;
  for (const Group* g : unconverged)
    if (listed.insert(g->Shot()).second)
      items.push_back("**unconverged** " + g->Shot() + ": " + CheckNumbers(*CheckOf(*g)));
  listed.clear();
  std::vector<std::string> unchecked_shots;
  for (const Group* g : unchecked)
    if (listed.insert(g->Shot()).second) unchecked_shots.push_back(g->Shot());
  if (!unchecked_shots.empty())
    items.push_back("**unchecked** (no convergence check in the store; kept in the overview): " +
                    Join(unchecked_shots, "; "));
  if (items.empty()) items.push_back("none: every shot's reference passed its convergence check");
  doc.List(items);

  BeyondThePapers(doc, included, engine_fits);
}

// A ratio to `none` with both intervals' worst cases as its interval.
// A cost ratio with the interval of its paired repetitions, where timed so:
// "≈ `none`" when the interval holds 1.
std::string CostText(const std::optional<BenchmarkCost>& cost) {
  if (!cost) return "n/a";
  if (cost->variant == "none") return "1";
  std::string text = Fmt(cost->ratio_to_none, "%.2f") + "×";
  if (cost->ratio_hi > 0) {
    text += " [" + Fmt(cost->ratio_lo, "%.2f") + ", " + Fmt(cost->ratio_hi, "%.2f") + "]";
    if (cost->ratio_lo <= 1 && cost->ratio_hi >= 1) text += " ≈ `none`";
  }
  return text;
}

// The kernel's static instruction count as a ratio to its batch's `none`,
// with the transcendental operations it adds: a cost no device's timing
// noise touches.
std::string InstructionText(const std::optional<BenchmarkCost>& cost) {
  if (!cost || cost->kernel.Total() == 0 || cost->none_kernel.Total() == 0) return "n/a";
  if (cost->variant == "none") return "1 (" + std::to_string(cost->kernel.Total()) + ")";
  const int more = cost->kernel.transcendental - cost->none_kernel.transcendental;
  return Fmt(double(cost->kernel.Total()) / cost->none_kernel.Total(), "%.2f") + "× (" + (more >= 0 ? "+" : "") +
         std::to_string(more) + " transc.)";
}

std::string RatioWithInterval(double value, Interval ci, double none_value, Interval none_ci) {
  if (std::isnan(value) || !(none_value > 0)) return "n/a";
  Interval ratio;
  if (ci.Known() && none_ci.Known() && none_ci.lo > 0) ratio = {ci.lo / none_ci.hi, ci.hi / none_ci.lo};
  return WithInterval(value / none_value, ratio, "%.3g");
}

// tv_err's ratio to `none`, with the interval the decision rule used: of
// the paired difference (relative to `none`'s tv_err) where the rows pair,
// else both intervals' worst cases.
std::string TvErrRatioText(const Evidence& e, const Evidence& none) {
  const std::optional<PairedComparison> paired = PairedTvErr(e, none);
  if (!paired || !(none.tv_err > 0)) return RatioWithInterval(e.tv_err, e.tv_err_ci, none.tv_err, none.tv_err_ci);
  return WithInterval(e.tv_err / none.tv_err, {1 + paired->ci.lo / none.tv_err, 1 + paired->ci.hi / none.tv_err},
                      "%.3g");
}

// The shot's reference: its convergence check, and how many rows its noise
// leaves unresolved (`noise`).
std::string ReferenceSentence(const Group& group, const std::string& noise) {
  std::string reference;
  switch (ConvergenceOf(group)) {
    case Convergence::kConverged:
      reference = "Reference: passed its convergence check" + noise + " (" + CheckNumbers(*CheckOf(group)) + ").";
      break;
    case Convergence::kUnconverged:
      reference = "Reference: **unconverged**, left out of the answer (" + CheckNumbers(*CheckOf(group)) + ").";
      break;
    case Convergence::kUnchecked:
      if (group.derivatives == kExternalDerivatives)
        reference = "Reference: each external sequence's own (unchecked: shimmer did not render it).";
      else
        reference = "Reference: **unchecked** (no convergence check in the store), " +
                    std::to_string(group.rows.front()->job.reference.spp) + " spp per axis" + noise + ".";
      break;
  }
  return reference;
}

// Where and how the rows' costs were timed.
std::string CostSentence(const Group& group) {
  std::set<std::string> bench_devices;
  const BenchmarkCost* bench = nullptr;
  for (const JobResult* r : group.rows)
    if (r->cost) bench_devices.insert(r->cost->device), bench = &*r->cost;
  std::string cost;
  if (bench_devices.empty())
    cost = "No benchmark: cost n/a.";
  else if (bench_devices.size() == 1 && bench->driver == "external")
    cost = "Cost: the external sequences' own, on " + bench->device + ", as a ratio to a `none` timed there.";
  else if (bench_devices.size() == 1)
    cost = "Cost: benchmark on " + bench->device + " at " + std::to_string(bench->width) + "×" +
           std::to_string(bench->height) + ", ratio to `none` in the same batch (on lavapipe: CPU time); "
           "beside it the kernel's static instruction count, ratio to `none`'s, and the transcendental "
           "operations it adds (docs/method.md, Cost).";
  else
    cost = "Cost: each row's ratio to `none` on its own benchmark device (report.csv, column bench_device).";
  return cost;
}

// Every other column, for report.html (report.csv has them all too).
void AllColumnsTable(Document& doc, const Group& group) {
  const Costs costs = CostsOf(group);
  std::vector<std::vector<std::string>> all;
  for (std::size_t i = 0; i < group.rows.size(); ++i) {
    const JobResult& r = *group.rows[i];
    const auto& m = r.metrics;
    all.push_back({Code(Label(r)), Region(r), WithInterval(Metric(m, "tv_err"), Ci95(r, "tv_err")),
                   WithInterval(Metric(m, "tv_ratio"), Ci95(r, "tv_ratio")),
                   WithInterval(Metric(m, "relmse_temporal"), Ci95(r, "relmse_temporal")),
                   WithInterval(Metric(m, "relmse_spatial"), Ci95(r, "relmse_spatial")),
                   WithInterval(FlickerIndex(m), Ci95(r, "flicker_index")), Fmt(Metric(m, "temporal_diff_err")),
                   Fmt(Metric(m, "tv_err_floor"), "%.2f"),
                   r.cost ? Fmt(r.cost->median_ms, "%.3g") + " (" + Fmt(r.cost->min_ms, "%.3g") + "–" +
                                Fmt(r.cost->max_ms, "%.3g") + ") on " + r.cost->device
                          : "n/a",
                   r.job.external && !(r.gpu_ms_per_frame > 0) ? std::string("n/a") : Fmt(r.gpu_ms_per_frame, "%.2f"),
                   std::string(costs.front_tv_err[i] ? "●" : "") + " / " + (costs.front_relmse[i] ? "●" : "")});
  }
  doc.HtmlOnlyTable({"variant", "region", "tv_err (luminance²) [95 %]", "tv_ratio [95 %]",
                     "joint error: temporal part [95 %]", "joint error: spatial part [95 %]",
                     "flicker_index [95 %]", "temporal_diff_err", "tv_err_floor", "bench ms (min–max)",
                     "render ms", "Pareto tv_err / relmse"},
                    all);
}

void ShotTable(Document& doc, const Group& group, bool has_video) {
  const std::string slug = Slug(group.key);
  doc.Heading(3, group.key);
  const JobResult* none = NoneOf(group);
  int unresolved = 0;
  if (none)
    for (const JobResult* r : group.rows)
      unresolved += r != none && Decide(EvidenceOf(*r), EvidenceOf(*none)) == Outcome::kUnresolved;
  const std::string noise =
      unresolved ? ", but " + std::to_string(unresolved) + " of its rows are **unresolved: reference noise**" : "";

  const std::string reference = ReferenceSentence(group, noise);
  const std::string cost = CostSentence(group);
  doc.Paragraph(reference + " " + cost +
                " The other columns are in report.csv and, folded under the table, in report.html (region, `tv_err` itself, `tv_ratio`, "
                "`flicker_index`, `tv_err_floor`, the temporal part of the joint error, ms).");
  doc.Figures({slug + "_pareto_tv_err.svg", slug + "_pareto_relmse.svg", slug + "_spectra.svg"},
              {"speed against tv_err", "speed against relmse", "flicker spectra"});
  if (has_video)
    doc.Paragraph("Video: [" + slug + kVideoSuffix + "](" + slug + kVideoSuffix +
                  "): the reference and up to 8 rows of this table (`none` first), each above its signed error "
                  "against the shot's reference, with the scale in the legend.");

  const Evidence base = none ? EvidenceOf(*none) : Evidence{};
  // The lowest joint error of the table, among the rows better than `none`.
  const JobResult* lowest = nullptr;
  for (const JobResult* r : group.rows)
    if (none && r != none && Decide(EvidenceOf(*r), base) == Outcome::kBetter &&
        (!lowest || Metric(r->metrics, "relmse") < Metric(lowest->metrics, "relmse")))
      lowest = r;
  std::vector<std::vector<std::string>> cells;
  for (const JobResult* r : group.rows) {
    const Evidence e = EvidenceOf(*r);
    const Outcome outcome = !none ? Outcome::kUnknown : r == none ? Outcome::kBaseline : Decide(e, base);
    std::string verdict = OutcomeText(outcome);
    if (r == lowest) verdict += ", lowest joint error";
    cells.push_back({Code(Label(*r)), WithInterval(e.joint, e.joint_ci, "%.3g"),
                     TvErrRatioText(e, base),
                     RatioWithInterval(e.spatial, e.spatial_ci, base.spatial, base.spatial_ci),
                     WithInterval(e.energy_bias, e.energy_ci, "%+.3f"),
                     CostText(r->cost), InstructionText(r->cost), verdict});
  }
  doc.Table({"variant", "joint error [95 %]", "tv_err, ratio to `none` [95 %]",
             "spatial error, ratio to `none` [95 %]", "energy bias, fraction [95 %]", "time, ratio to `none` [95 %]",
             "instructions, ratio to `none`", "verdict"},
            cells);
  AllColumnsTable(doc, group);
}

// Seed 004's approximations measured on their own, beside the shots that use them.
void SgAccuracySection(Document& doc, const SgAccuracyTable& sg) {
  const std::string stem = kSgAccuracyStem;
  doc.Heading(2, kSgAccuracyHeading);
  doc.Paragraph(
      "This store has shots lit by an SG light; the `sg-warp` and `asg-warp` variants shade them with "
      "seed 004's approximations, measured here on their own, without pixels or motion (`shimmer "
      "sg-accuracy`; numbers: [" +
      stem + ".csv](" + stem + ".csv)). " + SgAccuracyDescription(sg));
  const SgTextTable energy = SgEnergyTable(sg), relmse = SgRelmseTable(sg);
  doc.Paragraph("**Energy**, Σ approx / Σ exact − 1 (SG warp / ASG warp):");
  doc.Table(energy.header, energy.rows);
  doc.Paragraph("**relmse** (SG warp / ASG warp):");
  doc.Table(relmse.header, relmse.rows);
  doc.Figures({stem + ".svg"}, {"SG lighting: energy error against view angle per α, SG warp and ASG warp"});
}

// Seed 003's argument beside the measurements: what each normal-map filter
// stores per texel, and its error over the normal-mapped shots.
void NormalMapMemorySection(Document& doc, const std::vector<Group>& groups) {
  std::vector<const Group*> mapped;
  for (const Group& g : groups)
    if (NormalMappedScene(g)) mapped.push_back(&g);
  if (mapped.empty()) return;
  doc.Heading(2, kNormalMapMemoryHeading);
  doc.Paragraph(
      "Over the normal-mapped shots: each variant's median `tv_err` ratio to `none` (IQR), its energy bias, and "
      "what an engine stores per texel for it (docs/normal-maps.md): block-compressed where compression keeps the "
      "signal, 8-bit uncompressed where the mean normal's length is the signal, 16-bit floats for LEAN's moments "
      "(seed 003). Geometric filters and supersampling read the plain normal map.");
  std::vector<std::vector<std::string>> cells;
  for (const VariantSummary& v : Summarise(mapped)) {
    const TexelStorage s = NormalMapStorage(v.samples.front().row->job.variant);
    cells.push_back({Code(v.label), std::to_string(v.ratio.n), Ratio(v.ratio), Fmt(v.energy_bias.median, "%+.3f"),
                     s.format, Fmt(s.bytes, "%.3g")});
  }
  doc.Table({"variant", "tables", "tv_err ratio (IQR)", "energy bias", "stored per texel", "bytes per texel"},
            cells);
}

// A sparkle ratio with its 95 % interval where the row has one (rows
// measured before the intervals were kept show the ratio alone).
std::string SparkleRatio(const nlohmann::json& sparkles, const char* key) {
  std::string text = Fmt(Metric(sparkles, key), "%.3g");
  const auto ci = sparkles.find("ci95");
  if (ci == sparkles.end() || !ci->is_object()) return text;
  const auto i = ci->find(key);
  if (i == ci->end() || !i->is_array() || i->size() != 2 || !(*i)[0].is_number() || !(*i)[1].is_number())
    return text;
  return text + " " + Bounds((*i)[0].get<double>(), (*i)[1].get<double>());
}

// Glint shots (seed 001): what the eye sees of sparkles, beside tv_err. Rows
// measured with a sparkle threshold only (docs/metrics.md, "Sparkle
// statistics"); the reference's own statistics once per shot.
void SparkleSection(Document& doc, const std::vector<Group>& groups) {
  const auto number = Metric;  // any key of the metrics JSON, NaN when absent
  std::vector<std::vector<std::string>> cells;
  double threshold = kNaN;
  for (const Group& g : groups) {
    bool reference_row = false;
    for (const JobResult* r : g.rows) {
      const auto sp = r->metrics.find("sparkles");
      if (sp == r->metrics.end() || !sp->is_object()) continue;
      threshold = number(*sp, "threshold");
      const nlohmann::json none = nlohmann::json::object();
      const nlohmann::json& ref = sp->contains("reference") ? (*sp)["reference"] : none;
      if (!reference_row && !ref.empty()) {
        cells.push_back({g.Shot(), "reference", Fmt(number(ref, "mean_count"), "%.1f"),
                         Fmt(number(ref, "count_cv"), "%.3f"), Fmt(number(ref, "mean_lifetime"), "%.2f"), "", "",
                         "", ""});
        reference_row = true;
      }
      const nlohmann::json& test = (*sp)["test"];
      const JobResult* baseline = NoneOf(g);
      const Outcome outcome = !baseline        ? Outcome::kUnknown
                              : baseline == r ? Outcome::kBaseline
                                              : Decide(EvidenceOf(*r), EvidenceOf(*baseline));
      cells.push_back({g.Shot(), Code(r->job.variant), Fmt(number(test, "mean_count"), "%.1f"),
                       Fmt(number(test, "count_cv"), "%.3f"), Fmt(number(test, "mean_lifetime"), "%.2f"),
                       SparkleRatio(*sp, "mean_count_ratio"), SparkleRatio(*sp, "count_variance_ratio"),
                       SparkleRatio(*sp, "lifetime_ratio"), OutcomeText(outcome)});
    }
  }
  if (cells.empty()) return;
  doc.Heading(2, kSparklesHeading);
  doc.Paragraph("Sparkles: pixels whose luminance exceeds " + Fmt(threshold) +
                " in a frame (docs/metrics.md, \"Sparkle statistics\"). Count: sparkle pixels per frame, mean over "
                "the frames; CV: its standard deviation over time over the mean (how much the number of sparkles "
                "flickers); lifetime: mean frames a sparkle stays bright, tracked through the motion vectors. "
                "Ratios are the variant's over the reference's: 1 is the reference's glitter; in brackets their "
                "95 % interval (tiles and frame blocks resampled, the variant and the reference with the same "
                "draws).");
  doc.Table({"shot", "variant", "count", "count CV", "lifetime", "count ratio", "count variance ratio",
             "lifetime ratio", "verdict against `none`"},
            cells);
}

// Rows whose variant came from a user's file, named once with where the
// file was and what it held, so that a reader can tell them from the catalogue.
void UserVariantsSection(Document& doc, const std::vector<Group>& groups) {
  std::set<std::tuple<std::string, std::string, std::string>> files;
  for (const Group& g : groups)
    for (const JobResult* r : g.rows)
      if (!r->job.variant_hash.empty()) files.insert({r->job.variant, r->job.variant_file, r->job.variant_hash});
  if (files.empty()) return;
  doc.Heading(2, "Variants from files");
  doc.Paragraph(
      "These variants are users' GLSL files (docs/variants.md), measured like the catalogue's. The content hash is "
      "part of their job ids: an edited file is measured anew.");
  std::vector<std::vector<std::string>> cells;
  for (const auto& [name, file, hash] : files) cells.push_back({Code(name), Code(file), Code(hash)});
  doc.Table({"variant", "file", "content hash"}, cells);
}

// Rows from an engine's own frames, named once with where the frames were,
// what they held and the user's cost, so that a reader can tell them from
// what shimmer rendered.
void ExternalSequencesSection(Document& doc, const std::vector<Group>& groups) {
  std::map<std::string, const JobResult*> rows;  // by id: a row joins several derivative groups
  for (const Group& g : groups)
    for (const JobResult* r : g.rows)
      if (r->job.external) rows.emplace(r->id, r);
  if (rows.empty()) return;
  doc.Heading(2, kExternalHeading);
  doc.Paragraph(
      "These rows are frames rendered elsewhere (spec section `sequences`, docs/external.md), each measured "
      "against its own reference with the same metrics, intervals and region rules as the rendered rows, and "
      "labelled `(external)` in every table. A sequence that names a shot the spec renders sits in that shot's "
      "tables, beside its `none`; its ratio to `none` is meaningful only when both references show the same shot. "
      "Cost is the user's own time per frame on their device. The frames' content hashes are part of the job ids: "
      "frames rendered anew are measured anew.");
  std::vector<std::vector<std::string>> cells;
  for (const auto& [id, r] : rows) {
    const ExternalFrames& f = *r->job.external;
    cells.push_back({Code(Label(*r)), r->job.scene + " / " + r->job.material + " / " + r->job.camera, Code(f.test),
                     Code(f.reference), std::to_string(r->job.frames) + " × " + std::to_string(r->job.width) + "×" +
                                            std::to_string(r->job.height),
                     f.ms_per_frame > 0 ? Fmt(f.ms_per_frame, "%.3g") + " ms on " + f.device : "not given",
                     Code(f.test_hash)});
  }
  doc.Table({"label", "shot", "test", "reference", "frames", "cost", "content hash"}, cells);
}

}  // namespace

std::string Anchor(const std::string& heading) {
  // GitHub's: lower case, letters, digits, '-' and '_' kept (non-ASCII bytes
  // too), spaces to '-', the rest dropped; so links work in report.md there
  // and in report.html alike.
  std::string out;
  for (unsigned char c : heading) {
    if (c >= 0x80 || std::isalnum(c) || c == '-' || c == '_')
      out += char(c >= 0x80 ? c : std::tolower(c));
    else if (c == ' ')
      out += '-';
  }
  return out;
}

void Document::Heading(int level, const std::string& text) {
  Block b;
  b.kind = Block::Kind::kHeading, b.level = level, b.text = text, b.id = Anchor(text);
  blocks.push_back(std::move(b));
}
void Document::Paragraph(const std::string& text) {
  Block b;
  b.kind = Block::Kind::kParagraph, b.text = text;
  blocks.push_back(std::move(b));
}
void Document::List(std::vector<std::string> items) {
  Block b;
  b.kind = Block::Kind::kList, b.items = std::move(items);
  blocks.push_back(std::move(b));
}
void Document::Table(std::vector<std::string> header, std::vector<std::vector<std::string>> cells) {
  Block b;
  b.kind = Block::Kind::kTable, b.header = std::move(header), b.cells = std::move(cells);
  blocks.push_back(std::move(b));
}
void Document::HtmlOnlyTable(std::vector<std::string> header, std::vector<std::vector<std::string>> cells) {
  Table(std::move(header), std::move(cells));
  blocks.back().html_only = true;
}
void Document::Figures(std::vector<std::string> files, std::vector<std::string> captions) {
  Block b;
  b.kind = Block::Kind::kFigures, b.items = std::move(files), b.captions = std::move(captions);
  blocks.push_back(std::move(b));
}

// The precision the costs were timed to (each row's own: the spec's
// benchmark.precision when it was timed), and how many of them reached it.
static std::string CostPrecisionCount(const std::vector<const Group*>& groups) {
  std::set<const JobResult*> seen;
  std::set<double> precisions;
  std::size_t timed = 0, precise = 0;
  for (const Group* g : groups)
    for (const JobResult* r : g->rows) {
      if (!r->cost || r->job.variant == "none" || !seen.insert(r).second) continue;
      ++timed;
      const BenchmarkCost& c = *r->cost;
      precisions.insert(c.precision);
      precise += c.ratio_hi <= c.ratio_to_none * (1 + c.precision) && c.ratio_lo >= c.ratio_to_none * (1 - c.precision);
    }
  auto percent = [](double p) { return FormatNumber(100 * p, "%g") + " %"; };
  std::string within = "±" + (precisions.empty() ? percent(0.03) : percent(*precisions.begin()));
  if (precisions.size() > 1) within += " to ±" + percent(*precisions.rbegin());
  return "each variant timed until its interval is within " + within + " or the spec's cap was reached (" +
         std::to_string(precise) + " of " + std::to_string(timed) + " costs here reached it)";
}

Document BuildDocument(const std::vector<Group>& groups, const std::string& title, std::size_t jobs,
                       const SgAccuracyTable* sg, const std::set<std::string>* videos,
                       const std::vector<JointFit>& engine_fits) {
  std::set<std::string> devices;
  for (const Group& g : groups)
    for (const JobResult* r : g.rows)
      if (!r->job.external) devices.insert(DeviceOf(*r));  // shimmer rendered none of those
  if (devices.empty()) devices.insert("none (external sequences only)");
  std::vector<std::string> device_list(devices.begin(), devices.end());

  std::vector<const Group*> included, unconverged, unchecked;
  for (const Group& g : groups) switch (ConvergenceOf(g)) {
      case Convergence::kUnconverged: unconverged.push_back(&g); break;
      case Convergence::kUnchecked: unchecked.push_back(&g), included.push_back(&g); break;
      case Convergence::kConverged: included.push_back(&g); break;
    }
  const std::vector<CellAnswer> cells = AnswerCells(included);

  Document doc;
  doc.title = title;
  doc.Paragraph("Generated by `shimmer report` from " + std::to_string(jobs) + " jobs; metric renders on " +
                Join(device_list) + ". Which filter to use: the answer below; each shot's numbers: the Shots "
                "section; definitions: the Method. Raw rows: [report.csv](report.csv) (every column), the answer "
                "as [cells.csv](cells.csv); this report as one page: [report.html](report.html).");
  AnswerSection(doc, cells, BenchmarkDevices(included));
  const std::size_t contents = doc.blocks.size();
  Overview(doc, included, unconverged, unchecked, cells, engine_fits);
  if (sg) SgAccuracySection(doc, *sg);
  NormalMapMemorySection(doc, groups);
  SparkleSection(doc, groups);
  UserVariantsSection(doc, groups);
  ExternalSequencesSection(doc, groups);
  doc.Heading(2, kShotsHeading);
  doc.Paragraph(
      "Ordered by scene, roughness α, camera and derivative source. Values carry their 95 % interval in "
      "brackets. Verdict: the row against the table's `none` by the decision rule (Method); \"lowest joint "
      "error\" marks the best of the rows that are better than `none`.");
  for (const Group& g : groups) ShotTable(doc, g, videos && videos->count(g.key));
  doc.Heading(2, kMethodHeading);
  doc.Paragraph("**Decision rule.** " + DecisionRuleText());
  doc.Paragraph(
      "**Metrics** are defined in docs/metrics.md: the joint error `relmse` (mean over frames of the relative "
      "squared error against the reference frame, unitless) and its split into a temporal part (the error's "
      "weighted variance about each pixel's temporal mean) and a spatial part (that mean's error, "
      "`relmse_spatial`); `tv_err`, the temporal variance of the error against the supersampled reference "
      "(luminance², as a ratio to `none` in the tables); signed `energy_bias` (a fraction of the reference's "
      "energy); `flicker_index` (sensitivity-weighted error spectrum); `tv_err_floor`, the share of `tv_err` "
      "that the reference's own noise explains. Intervals are 95 % (reference error propagated, block bootstrap "
      "over frames and pixels); a ratio's interval combines the two intervals' worst cases. Region: the pixels "
      "measured (`highlight`: the reference's highlight mask). A reference passes its convergence check when "
      "`none` measured against it at N and at 2N samples per axis agrees within the spec's tolerances. Cost: "
      "dedicated benchmark renders, variants interleaved in one batch per device (the order reversed every "
      "repetition), the Hodges-Lehmann estimate of the paired per-repetition time ratios to `none` of the "
      "same batch with a Wilcoxon signed-rank 95 % interval, " +
      CostPrecisionCount(included) + "; on "
      "lavapipe this is CPU time. Beside it, a cost no timing noise touches: the kernel's static instruction "
      "count (its canonical SPIR-V, every function inlined) as a ratio to `none`'s, and the transcendental "
      "operations it adds. Pareto plots: no other variant of the "
      "table is both cheaper and lower in that error. Medians and quartiles interpolate linearly between order "
      "statistics.");
  // The table of contents: every section after the answer.
  std::vector<std::string> items;
  for (const Block& b : doc.blocks)
    if (b.kind == Block::Kind::kHeading && b.level == 2 && b.text != kAnswerHeading)
      items.push_back("[" + b.text + "](#" + b.id + ")");
  Block heading, list;
  heading.kind = Block::Kind::kHeading, heading.level = 2, heading.text = kContentsHeading,
  heading.id = Anchor(kContentsHeading);
  list.kind = Block::Kind::kList, list.items = std::move(items);
  doc.blocks.insert(doc.blocks.begin() + std::ptrdiff_t(contents), {heading, list});
  return doc;
}

}  // namespace shimmer::experiments::report
