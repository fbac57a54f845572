#include <algorithm>
#include <map>

#include "decision_rule.h"
#include "report_parts.h"
#include "shimmer/experiments/csv.h"

namespace shimmer::experiments::report {

namespace {

using Fields = std::vector<std::string>;

void Append(Fields& to, std::initializer_list<std::string> more) { to.insert(to.end(), more); }

constexpr const char* kIntervals[] = {"tv_err", "tv_ratio", "energy_bias", "relmse", "flicker_index"};
constexpr const char* kSplit[] = {"relmse_temporal", "relmse_spatial"};

// Columns are only ever added at the end, so that readers by position keep working.
Fields Header() {
  Fields header = {"scene",    "material", "camera",      "variant",           "params", "derivatives",   "region",
                   "tv_ratio", "tv_err",   "energy_bias", "temporal_diff_err", "relmse", "flicker_index", "ms_per_frame",
                   "device",   "driver"};
  for (const char* key : kIntervals) Append(header, {std::string(key) + "_lo", std::string(key) + "_hi"});
  Append(header, {"tv_err_floor", "reference", "reference_spp", "check_spp", "d_tv_ref", "d_energy_bias", "d_tv_err",
                  "bench_median_ms", "bench_min_ms", "bench_max_ms", "bench_ratio_to_none", "bench_width",
                  "bench_height", "bench_device", "bench_driver"});
  for (const char* key : kSplit) Append(header, {std::string(key), std::string(key) + "_lo", std::string(key) + "_hi"});
  Append(header, {"cell_row", "band", "verdict", "label", "tables", "sparkle_count_ratio"});
  // The reference noise's contrast (the decision rule's kVisibleContrast
  // test), the cost ratio's interval and repetitions, and the static
  // instruction counts of the row's kernel and of its batch's `none`.
  Append(header, {"ref_contrast", "bench_ratio_lo", "bench_ratio_hi", "bench_repetitions", "kernel_alu",
                  "kernel_transcendental", "kernel_memory", "kernel_control", "none_kernel_total"});
  // The paired comparison with the shot's `none` where their bootstrap
  // draws pair: tv_err's difference to `none`'s, its 95 % interval, and the
  // reference noise's share of that interval (decision_rule.h, NoiseShare).
  Append(header, {"tv_err_vs_none", "tv_err_vs_none_lo", "tv_err_vs_none_hi", "vs_none_noise_share"});
  // The glint part of the rule: the other two sparkle ratios, and whether
  // the variant is a glint material's smooth limit (1) or not (0).
  Append(header, {"sparkle_variance_ratio", "sparkle_lifetime_ratio", "smooth_limit"});
  return header;
}

// The job, its metrics and their intervals, its shot check and its benchmark time.
Fields MeasuredFields(const JobResult& r) {
  const auto& m = r.metrics;
  Fields fields = {r.job.scene,
                   r.job.material,
                   r.job.camera,
                   r.job.variant,
                   nlohmann::json(r.job.params).dump(),
                   r.job.derivatives,
                   Region(r),
                   CsvNumber(Metric(m, "tv_ratio")),
                   CsvNumber(Metric(m, "tv_err")),
                   CsvNumber(Metric(m, "energy_bias")),
                   CsvNumber(Metric(m, "temporal_diff_err")),
                   CsvNumber(Metric(m, "relmse")),
                   CsvNumber(FlickerIndex(m)),
                   CsvNumber(r.gpu_ms_per_frame),
                   r.device,
                   r.driver};
  for (const char* key : kIntervals) {
    const Interval ci = Ci95(r, key);
    Append(fields, {CsvNumber(ci.lo), CsvNumber(ci.hi)});
  }
  fields.push_back(CsvNumber(Metric(m, "tv_err_floor")));
  if (r.shot) {
    const ShotCheck& c = *r.shot;
    Append(fields, {c.converged ? "converged" : "unconverged", std::to_string(c.spp), std::to_string(c.check_spp),
                    CsvNumber(c.d_tv_ref), CsvNumber(c.d_energy_bias), CsvNumber(c.d_tv_err)});
  } else {
    Append(fields, {"unchecked", "", "", "", "", ""});
  }
  if (r.cost) {
    const BenchmarkCost& c = *r.cost;
    Append(fields, {CsvNumber(c.median_ms), CsvNumber(c.min_ms), CsvNumber(c.max_ms), CsvNumber(c.ratio_to_none),
                    std::to_string(c.width), std::to_string(c.height), c.device, c.driver});
  } else {
    Append(fields, {"", "", "", "", "", "", "", ""});
  }
  for (const char* key : kSplit) {
    const Interval ci = Ci95(r, key);
    Append(fields, {CsvNumber(Metric(m, key)), CsvNumber(ci.lo), CsvNumber(ci.hi)});
  }
  return fields;
}

// The cost ratio's interval and repetitions, and the kernels' instruction counts.
Fields CostFields(const JobResult& r) {
  Fields fields;
  if (r.cost && r.cost->ratio_hi > 0) {
    const BenchmarkCost& c = *r.cost;
    Append(fields, {CsvNumber(c.ratio_lo), CsvNumber(c.ratio_hi), std::to_string(c.repetitions)});
  } else {
    Append(fields, {"", "", r.cost ? std::to_string(r.cost->repetitions) : ""});
  }
  if (r.cost && r.cost->kernel.Total() > 0) {
    const shading::InstructionCensus& k = r.cost->kernel;
    Append(fields, {std::to_string(k.alu), std::to_string(k.transcendental), std::to_string(k.memory),
                    std::to_string(k.control), std::to_string(r.cost->none_kernel.Total())});
  } else {
    Append(fields, {"", "", "", "", ""});
  }
  return fields;
}

// What the decision rule read and said of r against its table's `none`
// (null: the shot has none), in the header's order from "cell_row" on.
Fields VerdictFields(const JobResult& r, const JobResult* none, int tables, Fields cost) {
  Group g;
  g.scene = r.job.scene, g.material = r.job.material, g.alpha = AlphaOf(r.job.material);
  g.rows = {&r};
  const Evidence evidence = EvidenceOf(r);
  const Outcome outcome = !none ? Outcome::kUnknown : none == &r ? Outcome::kBaseline : Decide(evidence, EvidenceOf(*none));
  std::string verdict = OutcomeText(outcome);
  verdict.erase(std::remove(verdict.begin(), verdict.end(), '*'), verdict.end());
  Fields fields = {CellRowOf(g),         RoughnessClass(g.alpha), verdict, Label(r), std::to_string(tables),
                   CsvNumber(evidence.sparkle_count_ratio), CsvNumber(evidence.noise_contrast)};
  fields.insert(fields.end(), cost.begin(), cost.end());
  const std::optional<PairedComparison> paired =
      !none || none == &r ? std::nullopt : PairedTvErr(evidence, EvidenceOf(*none));
  if (paired)
    Append(fields, {CsvNumber(paired->difference), CsvNumber(paired->ci.lo), CsvNumber(paired->ci.hi),
                    CsvNumber(paired->noise_share)});
  else
    Append(fields, {"", "", "", ""});
  Append(fields, {CsvNumber(evidence.sparkle_variance_ratio), CsvNumber(evidence.sparkle_lifetime_ratio),
                  evidence.smooth_limit ? "1" : "0"});
  return fields;
}

}  // namespace

std::string Csv(const std::vector<JobResult>& rows) {
  // Each row's verdict is against its shot's `none` (a derivative-reading
  // row's table has that same `none`).
  auto shot = [](const JobResult& r) { return r.job.scene + " / " + r.job.material + " / " + r.job.camera; };
  std::map<std::string, const JobResult*> none_of;
  for (const JobResult& r : rows)
    if (r.job.variant == "none" && (!r.job.external || !none_of.count(shot(r)))) none_of[shot(r)] = &r;
  // How many of the report's tables a row sits in: `none` and supersample-N
  // read no derivatives and join each derivative source's table of their shot.
  std::map<const JobResult*, int> tables;
  for (const Group& g : GroupRows(rows))
    for (const JobResult* r : g.rows) ++tables[r];
  CsvTable table(Header());
  for (const JobResult& r : rows) {
    Fields fields = MeasuredFields(r);
    const auto none = none_of.find(shot(r));
    const Fields verdict = VerdictFields(r, none == none_of.end() ? nullptr : none->second, tables[&r], CostFields(r));
    fields.insert(fields.end(), verdict.begin(), verdict.end());
    table.AddRow(fields);
  }
  return table.Text();
}

}  // namespace shimmer::experiments::report
