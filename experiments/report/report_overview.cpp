// The overview across shots: per-variant summaries, roughness and geometry
// classes, and the recommendation per class.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "report_parts.h"
#include "shimmer/experiments/output_files.h"

namespace shimmer::experiments::report {

namespace {

double MedianOf(const std::vector<double>& v) { return QuartilesOf(v).median; }

// A class's recommendation asks for evidence from most of its tables.
constexpr double kCoverage = 0.75;

bool SortsBefore(const VariantSummary& a, const VariantSummary& b) {
  const bool a_known = !std::isnan(a.ratio.median), b_known = !std::isnan(b.ratio.median);
  if (a_known != b_known) return a_known;
  if (a_known && a.ratio.median != b.ratio.median) return a.ratio.median < b.ratio.median;
  return a.label < b.label;
}

// The one benchmark device of a summary's costs, when there is exactly one.
const Quartiles* SoleCost(const VariantSummary& v) {
  return v.cost_ratio.size() == 1 ? &v.cost_ratio.begin()->second : nullptr;
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
      if (!std::isnan(s.energy_bias)) ++with_bias, within += std::abs(s.energy_bias) <= kBiasTolerance;
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

Verdict ClassVerdict(int better, int worse, int overlapping) {
  const int known = better + worse + overlapping;
  if (known == 0) return Verdict::kUnknown;
  if (worse == 0 && 2 * better >= known) return Verdict::kBetter;
  return Verdict::kIndistinguishable;
}

std::string RecommendationRule() {
  return "Per class (shots lit by a spherical Gaussian form their own class, since they run their own variants), "
         "a variant other than `none` qualifies when it was measured in at least 3/4 of the class's "
         "tables and its |energy_bias| stays within 0.10 in at least 3/4 of those. The pick is the qualifier with the "
         "lowest median `tv_err` ratio to `none`, provided that median is below 1 (else: keep `none`). "
         "`supersample-N` is the brute-force baseline: it qualifies only when its median benchmark cost ratio is "
         "known and at most the best filter's (without a qualifying filter it is only named). The runner-up is the "
         "next qualifier; the pick is called better than "
         "it only when the pick's 95 % interval of `tv_err` lies below the runner-up's in at least half of their "
         "shared tables and above it in none, else they are indistinguishable. Gain: median ratio over the class's "
         "tables with its interquartile range, and the medians of the per-table 95 % bounds of the ratio (each the "
         "worst case of the two intervals).";
}

std::vector<Recommendation> Recommend(const std::vector<const Group*>& groups) {
  std::map<std::pair<int, std::string>, std::vector<const Group*>> classes;
  static const std::vector<std::string> kRoughness = {"α ≤ 0.02", "0.02 < α ≤ 0.1", "0.1 < α ≤ 0.3", "α > 0.3",
                                                      "α unknown"};
  static const std::vector<std::string> kGeometry = {"small curved", "thin", "flat with normal detail", "other"};
  auto rank = [](const std::vector<std::string>& order, const std::string& name) {
    return int(std::find(order.begin(), order.end(), name) - order.begin());
  };
  for (const Group* g : groups) {
    // SG-lit shots run their own variant list: in the delta-lit classes they
    // would count as tables the other filters were not measured in.
    if (SgLitScene(g->scene)) {
      classes[{200, "light"}].push_back(g);
      continue;
    }
    // Likewise the normal-mapped shots and their normal-map filters.
    if (NormalMappedScene(g->scene)) {
      classes[{150, "normal maps"}].push_back(g);
      continue;
    }
    classes[{rank(kRoughness, RoughnessClass(g->alpha)), "roughness"}].push_back(g);
    classes[{100 + rank(kGeometry, GeometryClass(g->scene)), "geometry"}].push_back(g);
  }
  std::vector<Recommendation> out;
  for (auto& [key, members] : classes) {
    Recommendation rec;
    rec.dimension = key.second;
    rec.name = rec.dimension == "roughness"     ? RoughnessClass(members.front()->alpha)
               : rec.dimension == "light"       ? "spherical Gaussian"
               : rec.dimension == "normal maps" ? "normal-mapped"
                                                : GeometryClass(members.front()->scene);
    rec.tables = int(members.size());
    std::set<std::string> shots;
    for (const Group* g : members) shots.insert(g->Shot());
    rec.shots = int(shots.size());
    rec.summaries = Summarise(members);
    auto qualifies = [&](const VariantSummary& v) {
      return !v.none && v.ratio.n >= kCoverage * rec.tables && v.energy_share >= kCoverage;
    };
    for (const VariantSummary& v : rec.summaries)
      if (!v.supersample && qualifies(v) && !std::isnan(v.ratio.median)) {
        rec.pick = &v;
        break;
      }
    // A supersample-N that beats the pick at no greater cost takes its place.
    const Quartiles* pick_cost = rec.pick ? SoleCost(*rec.pick) : nullptr;
    const VariantSummary* brute_force = nullptr;
    for (const VariantSummary& v : rec.summaries) {
      if (!v.supersample || !qualifies(v) || std::isnan(v.ratio.median)) continue;
      const Quartiles* cost = SoleCost(v);
      if (!rec.pick) {
        if (!brute_force) brute_force = &v;  // the steadiest, summaries being sorted by ratio
        continue;
      }
      const bool cheap_enough = cost && pick_cost &&
                                rec.pick->cost_ratio.begin()->first == v.cost_ratio.begin()->first &&
                                cost->median <= pick_cost->median;
      if (cheap_enough && v.ratio.median < rec.pick->ratio.median) rec.pick = &v;
    }
    if (rec.pick && !(rec.pick->ratio.median < 1)) {
      rec.note = "the best qualifier, `" + rec.pick->label + "`, does not lower tv_err";
      rec.pick = nullptr;
    } else if (!rec.pick) {
      rec.note = "no filter keeps energy within ±10 % in 3/4 of the tables";
      if (brute_force)
        rec.note +=
            "; brute force: `" + brute_force->label + "` at ratio " + FormatNumber(brute_force->ratio.median, "%.3g");
    }
    if (rec.pick)
      for (const VariantSummary& v : rec.summaries)
        if (&v != rec.pick && qualifies(v) && !std::isnan(v.ratio.median) &&
            (!v.supersample || (SoleCost(v) && pick_cost && SoleCost(v)->median <= pick_cost->median))) {
          rec.runner_up = &v;
          break;
        }
    if (rec.runner_up) {
      std::map<const Group*, const JobResult*> runner_rows;
      for (const Sample& s : rec.runner_up->samples) runner_rows[s.group] = s.row;
      for (const Sample& s : rec.pick->samples) {
        auto other = runner_rows.find(s.group);
        if (other == runner_rows.end()) continue;
        switch (Compare(Ci95(*s.row, "tv_err"), Ci95(*other->second, "tv_err"))) {
          case Verdict::kBetter: ++rec.better; break;
          case Verdict::kWorse: ++rec.worse; break;
          case Verdict::kIndistinguishable: ++rec.overlapping; break;
          case Verdict::kUnknown: ++rec.unknown; break;
        }
      }
      rec.verdict = ClassVerdict(rec.better, rec.worse, rec.overlapping);
    }
    out.push_back(std::move(rec));
  }
  return out;
}

}  // namespace shimmer::experiments::report
