// What the report says, in order: the overview across shots (leaderboard,
// heatmap, recommendations, shots left out), the per-shot tables, the method.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "report_document.h"
#include "shimmer/experiments/output_files.h"
#include "shimmer/experiments/report.h"

namespace shimmer::experiments::report {

namespace {

std::string Fmt(double v, const char* f = "%.4g") { return std::isnan(v) ? "n/a" : FormatNumber(v, f); }

std::string WithInterval(double v, Interval ci, const char* f = "%.4g") {
  if (std::isnan(v)) return "n/a";
  std::string text = FormatNumber(v, f);
  if (ci.Known()) text += " [" + FormatNumber(ci.lo, f) + ", " + FormatNumber(ci.hi, f) + "]";
  return text;
}

std::string Percent(double share) { return std::isnan(share) ? "n/a" : FormatNumber(100 * share, "%.0f") + " %"; }

std::string Code(const std::string& s) { return "`" + s + "`"; }

std::string Join(const std::vector<std::string>& items, const std::string& sep = ", ") {
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

// Cost ratios of one variant, one entry per benchmark device.
std::string CostText(const VariantSummary& v, const std::vector<std::string>& devices, bool name_device) {
  std::vector<std::string> parts;
  for (const std::string& d : devices) {
    auto it = v.cost_ratio.find(d);
    if (it == v.cost_ratio.end()) continue;
    parts.push_back(Fmt(it->second.median, "%.2f") + "×" + (name_device ? " on " + d : ""));
  }
  return parts.empty() ? "n/a" : Join(parts, "; ");
}

std::string CheckNumbers(const ShotCheck& c) {
  return "spp " + std::to_string(c.spp) + " vs " + std::to_string(c.check_spp) + " per axis; changes: tv_ref " +
         Fmt(c.d_tv_ref, "%.3g") + " (tolerance " + Fmt(c.tol_tv, "%.3g") + "), energy_bias " +
         Fmt(c.d_energy_bias, "%.3g") + " (tolerance " + Fmt(c.tol_energy, "%.3g") + "), tv_err " +
         Fmt(c.d_tv_err, "%.3g") + " (tolerance " + Fmt(c.tol_tv, "%.3g") + ")" +
         (c.unconverged_pixels ? "; " + std::to_string(c.unconverged_pixels) + " pixel-frames above tolerance" : "");
}

std::string VerdictText(Verdict v) {
  switch (v) {
    case Verdict::kBetter: return "better";
    case Verdict::kWorse: return "worse";
    case Verdict::kIndistinguishable: return "indistinguishable";
    case Verdict::kUnknown: break;
  }
  return "n/a (no intervals)";
}

void Overview(Document& doc, const std::vector<Group>& groups, const std::vector<JointFit>& engine_fits) {
  std::vector<const Group*> included;
  std::vector<const Group*> unconverged, unchecked;
  for (const Group& g : groups) switch (ConvergenceOf(g)) {
      case Convergence::kUnconverged: unconverged.push_back(&g); break;
      case Convergence::kUnchecked: unchecked.push_back(&g), included.push_back(&g); break;
      case Convergence::kConverged: included.push_back(&g); break;
    }
  const std::vector<VariantSummary> summaries = Summarise(included);
  const std::vector<std::string> devices = BenchmarkDevices(included);
  std::set<std::string> shots;
  for (const Group* g : included) shots.insert(g->Shot());

  doc.Heading(2, kOverviewHeading);
  doc.Paragraph(std::to_string(included.size()) + " tables (" + std::to_string(shots.size()) +
                " shots × derivative sources) enter the overview; unconverged shots are left out (listed below). "
                "Ratio: a variant's `tv_err` over `none`'s in the same table (below 1: steadier). Cost: benchmark "
                "GPU time over `none`'s in the same batch" +
                (devices.empty() ? std::string(" (no benchmark in this store: n/a)")
                                 : ", on " + Join(devices, " and ") + (devices.size() > 1 ? ", one column each" : "")) +
                ".");

  doc.Heading(3, kLeaderboardHeading);
  std::vector<std::string> header = {"variant", "tables", "median ratio (IQR)", "median 95 % bounds",
                                     "|energy_bias| ≤ 0.10"};
  for (const std::string& d : devices) header.push_back(devices.size() > 1 ? "cost ×none on " + d : "cost ×none");
  if (devices.empty()) header.push_back("cost ×none");
  std::vector<std::vector<std::string>> cells;
  for (const VariantSummary& v : summaries) {
    std::vector<std::string> row = {Code(v.label), std::to_string(v.ratio.n), Ratio(v.ratio),
                                    Bounds(v.ratio_lo, v.ratio_hi), Percent(v.energy_share)};
    for (const std::string& d : devices) {
      auto it = v.cost_ratio.find(d);
      row.push_back(it == v.cost_ratio.end() ? "n/a" : Fmt(it->second.median, "%.2f"));
    }
    if (devices.empty()) row.push_back("n/a");
    cells.push_back(std::move(row));
  }
  doc.Table(header, cells);

  doc.Heading(3, kHeatmapHeading);
  doc.Paragraph(
      "log10 of the `tv_err` ratio to `none` per variant and table: blue is steadier than `none`, red less "
      "steady; × marks |energy_bias| > 0.10.");
  doc.Figures({"heatmap.svg"}, {"variants × shots: log10 tv_err ratio to none"});

  doc.Heading(3, kRecommendationsHeading);
  doc.Paragraph(RecommendationRule());
  cells.clear();
  for (const Recommendation& r : Recommend(included)) {
    std::vector<std::string> row = {r.dimension + ": " + r.name,
                                    std::to_string(r.tables) + " (" + std::to_string(r.shots) + " shots)"};
    if (!r.pick) {
      row.insert(row.end(), {"keep `none`: " + r.note, "", "", "", "", ""});
    } else {
      const VariantSummary& p = *r.pick;
      row.push_back("**" + Code(p.label) + "**");
      row.push_back(Ratio(p.ratio) + ", 95 % " + Bounds(p.ratio_lo, p.ratio_hi));
      row.push_back(Fmt(p.energy_bias.median, "%+.3f") + " (within ±10 % in " + Percent(p.energy_share) + ")");
      row.push_back(CostText(p, devices, devices.size() > 1));
      row.push_back(r.runner_up ? Code(r.runner_up->label) + " " + Fmt(r.runner_up->ratio.median, "%.3g")
                                : "no other qualifier");
      row.push_back(r.runner_up
                        ? VerdictText(r.verdict) + " (lower in " + std::to_string(r.better) + ", overlapping in " +
                              std::to_string(r.overlapping) + ", higher in " + std::to_string(r.worse) +
                              (r.unknown ? ", no intervals in " + std::to_string(r.unknown) : "") + ")"
                        : "n/a");
    }
    cells.push_back(std::move(row));
  }
  doc.Table(
      {"class", "tables", "pick", "gain: tv_err ratio", "energy bias", "cost ×none", "runner-up", "pick vs runner-up"},
      cells);

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
  if (items.empty()) items.push_back("none: every shot's reference was shown converged");
  doc.List(items);

  BeyondThePapers(doc, included, engine_fits);
}

void ShotTable(Document& doc, const Group& group, bool has_video) {
  const Costs costs = CostsOf(group);
  const std::vector<Sample> samples = SamplesOf(group);
  const std::string slug = Slug(group.key);
  doc.Heading(3, group.key);

  std::string reference;
  switch (ConvergenceOf(group)) {
    case Convergence::kConverged:
      reference = "Reference: **converged** (" + CheckNumbers(*CheckOf(group)) + ").";
      break;
    case Convergence::kUnconverged:
      reference = "Reference: **unconverged**, left out of the overview (" + CheckNumbers(*CheckOf(group)) + ").";
      break;
    case Convergence::kUnchecked:
      if (group.derivatives == kExternalDerivatives)
        reference = "Reference: each external sequence's own (unchecked: shimmer did not render it).";
      else
        reference = "Reference: **unchecked** (no convergence check in the store), " +
                    std::to_string(group.rows.front()->job.reference.spp) + " spp per axis.";
      break;
  }
  std::set<std::string> bench_devices;
  const BenchmarkCost* bench = nullptr;
  for (const JobResult* r : group.rows)
    if (r->cost) bench_devices.insert(r->cost->device), bench = &*r->cost;
  std::string cost;
  if (bench_devices.empty())
    cost = "No benchmark: cost ×none n/a; render ms is the metric render's own GPU time (small renders, noisy).";
  else if (bench_devices.size() == 1 && bench->driver == "external")
    cost = "Cost: the external sequences' own, on " + bench->device + "; cost ×none is to a `none` timed there.";
  else if (bench_devices.size() == 1)
    cost = "Benchmark on " + bench->device + " (" + bench->driver + "), " + std::to_string(bench->width) + "×" +
           std::to_string(bench->height) + ", " + std::to_string(bench->repetitions) +
           " repetitions; cost ×none is to `none` in the same batch.";
  else
    cost = "Benchmarks from " + std::to_string(bench_devices.size()) +
           " devices: each row's cost ×none is to `none` on its own device (column bench device); no ratio across "
           "devices.";
  doc.Paragraph(reference + " " + cost + " Pareto cost: " + costs.source + ".");
  doc.Figures({slug + "_pareto_tv_err.svg", slug + "_pareto_relmse.svg", slug + "_spectra.svg"},
              {"speed against tv_err", "speed against relmse", "flicker spectra"});
  if (has_video)
    doc.Paragraph("Video: [" + slug + kVideoSuffix + "](" + slug + kVideoSuffix +
                  "): the reference and up to 8 rows of this table (`none` first), each above its signed error "
                  "against the shot's reference, with the scale in the legend.");

  // The shot's best: the lowest tv_err within ±10 % energy (filters only); rows
  // whose interval overlaps its are indistinguishable from it.
  int best = -1;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const JobResult& r = *samples[i].row;
    const double err = Metric(r.metrics, "tv_err");
    if (IsSupersample(r) || std::isnan(err) || !(std::abs(samples[i].energy_bias) <= kBiasTolerance)) continue;
    if (best < 0 || err < Metric(samples[best].row->metrics, "tv_err")) best = int(i);
  }
  const bool many_devices = bench_devices.size() > 1;
  std::vector<std::string> header = {"variant",
                                     "region",
                                     "tv_err [95 %]",
                                     "tv_err ×none",
                                     "vs best",
                                     "tv_ratio [95 %]",
                                     "energy_bias [95 %]",
                                     "relmse [95 %]",
                                     "flicker_index [95 %]",
                                     "temporal_diff_err",
                                     "tv_err_floor",
                                     "cost ×none",
                                     "bench ms (min–max)"};
  if (many_devices) header.push_back("bench device");
  header.insert(header.end(), {"render ms", "Pareto tv_err", "Pareto relmse"});
  std::vector<std::vector<std::string>> cells;
  std::vector<std::string> alike;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const JobResult& r = *samples[i].row;
    const auto& m = r.metrics;
    std::string vs = "n/a";
    if (int(i) == best) {
      vs = "**best**";
    } else if (best >= 0) {
      switch (Compare(Ci95(r, "tv_err"), Ci95(*samples[best].row, "tv_err"))) {
        case Verdict::kBetter: vs = "lower"; break;
        case Verdict::kWorse: vs = "higher"; break;
        case Verdict::kIndistinguishable: vs = "≈ indistinguishable", alike.push_back(Code(Label(r))); break;
        case Verdict::kUnknown: break;
      }
    }
    std::vector<std::string> row = {Code(Label(r)),
                                    Region(r),
                                    WithInterval(Metric(m, "tv_err"), Ci95(r, "tv_err")),
                                    Fmt(samples[i].ratio, "%.3g"),
                                    vs,
                                    WithInterval(Metric(m, "tv_ratio"), Ci95(r, "tv_ratio")),
                                    WithInterval(Metric(m, "energy_bias"), Ci95(r, "energy_bias"), "%+.3f"),
                                    WithInterval(Metric(m, "relmse"), Ci95(r, "relmse")),
                                    WithInterval(FlickerIndex(m), Ci95(r, "flicker_index")),
                                    Fmt(Metric(m, "temporal_diff_err")),
                                    Fmt(Metric(m, "tv_err_floor"), "%.2f"),
                                    r.cost ? Fmt(r.cost->ratio_to_none, "%.2f") : "n/a",
                                    r.cost ? Fmt(r.cost->median_ms, "%.3g") + " (" + Fmt(r.cost->min_ms, "%.3g") + "–" +
                                                 Fmt(r.cost->max_ms, "%.3g") + ")"
                                           : "n/a"};
    if (many_devices) row.push_back(r.cost ? r.cost->device : "n/a");
    row.insert(row.end(),
               {r.job.external && !(r.gpu_ms_per_frame > 0) ? std::string("n/a") : Fmt(r.gpu_ms_per_frame, "%.2f"), costs.front_tv_err[i] ? "●" : "", costs.front_relmse[i] ? "●" : ""});
    cells.push_back(std::move(row));
  }
  doc.Table(header, cells);
  if (best >= 0)
    doc.Paragraph("Lowest `tv_err` within ±10 % energy: " + Code(Label(*samples[best].row)) + " (ratio to `none` " +
                  Fmt(samples[best].ratio, "%.3g") +
                  "); indistinguishable from it: " + (alike.empty() ? std::string("none") : Join(alike)) + ".");
  else
    doc.Paragraph("No filter stays within ±10 % energy in this table.");
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
    if (NormalMappedScene(g.scene)) mapped.push_back(&g);
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
                         ""});
        reference_row = true;
      }
      const nlohmann::json& test = (*sp)["test"];
      cells.push_back({g.Shot(), Code(r->job.variant), Fmt(number(test, "mean_count"), "%.1f"),
                       Fmt(number(test, "count_cv"), "%.3f"), Fmt(number(test, "mean_lifetime"), "%.2f"),
                       Fmt(number(*sp, "mean_count_ratio"), "%.3g"), Fmt(number(*sp, "count_variance_ratio"), "%.3g"),
                       Fmt(number(*sp, "lifetime_ratio"), "%.3g")});
    }
  }
  if (cells.empty()) return;
  doc.Heading(2, kSparklesHeading);
  doc.Paragraph("Sparkles: pixels whose luminance exceeds " + Fmt(threshold) +
                " in a frame (docs/metrics.md, \"Sparkle statistics\"). Count: sparkle pixels per frame, mean over "
                "the frames; CV: its standard deviation over time over the mean (how much the number of sparkles "
                "flickers); lifetime: mean frames a sparkle stays bright, tracked through the motion vectors. "
                "Ratios are the variant's over the reference's: 1 is the reference's glitter.");
  doc.Table({"shot", "variant", "count", "count CV", "lifetime", "count ratio", "count variance ratio",
             "lifetime ratio"},
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

void Document::Heading(int level, const std::string& text) {
  Block b;
  b.kind = Block::Kind::kHeading, b.level = level, b.text = text, b.id = Slug(text);
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
void Document::Figures(std::vector<std::string> files, std::vector<std::string> captions) {
  Block b;
  b.kind = Block::Kind::kFigures, b.items = std::move(files), b.captions = std::move(captions);
  blocks.push_back(std::move(b));
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

  Document doc;
  doc.title = title;
  doc.Paragraph("Generated by `shimmer report` from " + std::to_string(jobs) + " jobs; metric renders on " +
                Join(device_list) + ". Which filter to use: the overview; each shot's numbers: the tables below; " +
                "definitions: the method at the end. Raw rows: [report.csv](report.csv); this report as one page: " +
                "[report.html](report.html).");
  Overview(doc, groups, engine_fits);
  if (sg) SgAccuracySection(doc, *sg);
  NormalMapMemorySection(doc, groups);
  SparkleSection(doc, groups);
  UserVariantsSection(doc, groups);
  ExternalSequencesSection(doc, groups);
  doc.Heading(2, kShotsHeading);
  doc.Paragraph(
      "Ordered by scene, roughness α, camera and derivative source. Values carry their 95 % interval in "
      "brackets where the store has one. vs best: the row against the table's lowest `tv_err` within ±10 % "
      "energy (filters, not supersample-N); `≈ indistinguishable` when the intervals overlap, `lower`/"
      "`higher` only when they separate.");
  for (const Group& g : groups) ShotTable(doc, g, videos && videos->count(g.key));
  doc.Heading(2, kMethodHeading);
  doc.Paragraph(
      "Metrics are defined in docs/metrics.md: temporal variance of the error against the supersampled reference "
      "(`tv_err`), its ratio to the reference's own (`tv_ratio`), signed `energy_bias`, `temporal_diff_err`, spatial "
      "`relmse`, `flicker_index` (sensitivity-weighted error spectrum); `tv_err_floor` is the share of `tv_err` that "
      "the reference's own noise explains (near 1: the reference cannot resolve the difference). Intervals are 95 % "
      "(reference error propagated, block bootstrap over frames and pixels). Region: the pixels measured "
      "(`highlight`: the reference's highlight mask). A reference is converged when `none` measured against it at N "
      "and at 2N samples per axis agrees within the spec's tolerances. Cost: dedicated benchmark renders, variants "
      "interleaved in one batch per device, median GPU ms per frame with min–max, as a ratio to `none` of the same "
      "batch; render ms is the metric render's own time, used for a Pareto front only without a benchmark. Pareto: "
      "no other variant of the table is both cheaper and lower in that error; `supersample-N` is the brute-force "
      "baseline. Medians and quartiles interpolate linearly between order statistics.");
  return doc;
}

}  // namespace shimmer::experiments::report
