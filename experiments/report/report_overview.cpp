// Per-variant summaries across shots (the heatmap's order, the normal-map
// memory table, the parts beyond the papers) and the benchmark devices.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "decision_rule.h"
#include "report_parts.h"
#include "shimmer/experiments/output_files.h"

namespace shimmer::experiments::report {

namespace {

double MedianOf(const std::vector<double>& v) { return QuartilesOf(v).median; }

bool SortsBefore(const VariantSummary& a, const VariantSummary& b) {
  const bool a_known = !std::isnan(a.ratio.median), b_known = !std::isnan(b.ratio.median);
  if (a_known != b_known) return a_known;
  if (a_known && a.ratio.median != b.ratio.median) return a.ratio.median < b.ratio.median;
  return a.label < b.label;
}

}  // namespace

std::vector<VariantSummary> Summarise(const std::vector<const Group*>& groups) {
  std::map<std::string, VariantSummary> by_label;
  for (const Group* g : groups)
    for (const Sample& s : SamplesOf(*g)) {
      VariantSummary& v = by_label[Label(*s.row)];
      v.label = Label(*s.row);
      v.supersample = IsSupersample(*s.row);
      v.none = s.row->job.variant == "none";
      v.samples.push_back(s);
    }
  std::vector<VariantSummary> out;
  for (auto& [label, v] : by_label) {
    std::vector<double> ratio, lo, hi, bias;
    std::map<std::string, std::vector<double>> cost;
    int within = 0, with_bias = 0;
    for (const Sample& s : v.samples) {
      ratio.push_back(s.ratio);
      lo.push_back(s.ratio_ci.lo);
      hi.push_back(s.ratio_ci.hi);
      bias.push_back(s.energy_bias);
      if (!std::isnan(s.energy_bias)) ++with_bias, within += std::abs(s.energy_bias) <= kEnergyTolerance;
      if (s.row->cost) cost[s.row->cost->device].push_back(s.row->cost->ratio_to_none);
    }
    v.ratio = QuartilesOf(ratio);
    v.ratio_lo = MedianOf(lo), v.ratio_hi = MedianOf(hi);
    v.energy_bias = QuartilesOf(bias);
    v.energy_share = with_bias ? double(within) / with_bias : kNaN;
    for (const auto& [device, values] : cost) v.cost_ratio[device] = QuartilesOf(values);
    out.push_back(std::move(v));
  }
  std::sort(out.begin(), out.end(), SortsBefore);
  return out;
}

std::vector<std::string> BenchmarkDevices(const std::vector<const Group*>& groups) {
  std::set<std::string> devices;
  for (const Group* g : groups)
    for (const JobResult* r : g->rows)
      if (r->cost) devices.insert(r->cost->device);
  return {devices.begin(), devices.end()};
}

}  // namespace shimmer::experiments::report
