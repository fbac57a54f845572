#include "decision_rule.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "shimmer/experiments/output_files.h"
#include "shimmer/shading/shading.h"

namespace shimmer::experiments::report {

namespace {

bool Meets(const Interval& energy, double point) {
  if (energy.Known()) return energy.lo <= kEnergyTolerance && energy.hi >= -kEnergyTolerance;
  return std::abs(point) <= kEnergyTolerance;
}

// A ratio to the reference inside [1/tolerance, tolerance]; NaN (no sparkle
// statistics, or none in the reference) passes, 0 (no sparkle at all) does not.
bool Within(double ratio, double tolerance) { return !(ratio < 1 / tolerance || ratio > tolerance); }

bool KeepsGlints(const Evidence& v) {
  return Within(v.sparkle_count_ratio, kSparkleTolerance) &&
         Within(v.sparkle_variance_ratio, kSparkleTolerance * kSparkleTolerance) &&
         Within(v.sparkle_lifetime_ratio, kSparkleTolerance);
}

// The material spec of a glint material (docs/glints.md): its rows form the
// answer's "glints" row and are judged by their sparkles, not their blur.
bool IsGlintMaterial(const std::string& material) { return material.rfind("glints", 0) == 0; }

bool Near(double value, double baseline) {
  if (std::isnan(value) || std::isnan(baseline)) return false;
  if (baseline == 0) return value == 0;
  return std::abs(value / baseline - 1) <= kNilEffect;
}

const std::vector<std::string> kRows = {"small curved", "thin", "flat with normal detail", "other",
                                        "normal-mapped", "SG-lit",       "glints"};
const std::vector<std::string> kBands = {"α ≤ 0.02", "0.02 < α ≤ 0.1", "0.1 < α ≤ 0.3", "α > 0.3", "α unknown"};

}  // namespace

Evidence EvidenceOf(const JobResult& row) {
  Evidence e;
  e.tv_err = Metric(row.metrics, "tv_err");
  e.joint = Metric(row.metrics, "relmse");
  e.energy_bias = Metric(row.metrics, "energy_bias");
  e.noise_share = Metric(row.metrics, "tv_err_floor");
  e.tv_err_ci = Ci95(row, "tv_err");
  e.joint_ci = Ci95(row, "relmse");
  e.energy_ci = Ci95(row, "energy_bias");
  e.spatial = Metric(row.metrics, "relmse_spatial");
  e.spatial_ci = Ci95(row, "relmse_spatial");
  if (std::isnan(e.spatial)) e.spatial = e.joint, e.spatial_ci = e.joint_ci;
  const double noise = Metric(row.metrics, "ref_noise"), mean = Metric(row.metrics, "ref_mean");
  if (noise >= 0 && mean > 0) e.noise_contrast = std::sqrt(noise) / mean;
  if (auto sp = row.metrics.find("sparkles"); sp != row.metrics.end() && sp->is_object()) {
    e.sparkle_count_ratio = Metric(*sp, "mean_count_ratio");
    e.sparkle_variance_ratio = Metric(*sp, "count_variance_ratio");
    e.sparkle_lifetime_ratio = Metric(*sp, "lifetime_ratio");
  }
  e.glint = IsGlintMaterial(row.job.material);
  const shading::VariantInfo* info = shading::FindVariant(row.job.variant);
  e.smooth_limit = info && info->smooth_limit;
  e.draws = row.draws;
  e.reference_id = row.reference_id;
  e.tv_test = Metric(row.metrics, "tv_test");
  e.ref_noise = Metric(row.metrics, "ref_noise");
  e.joint_noise_sigma = Metric(row.metrics, "relmse_noise_sigma");
  e.frames = row.metrics.value("frames", 0);
  e.pixels = row.metrics.value("pixels", 0LL);
  return e;
}

namespace {

// Same draws (region, frames, seed) and the same reference: an external
// sequence measured against its own reference does not pair with shimmer's rows.
bool Pair(const Evidence& a, const Evidence& b) {
  return a.draws && b.draws && a.draws->key == b.draws->key && a.reference_id == b.reference_id;
}

// The bootstrap interval of a - b widened in quadrature by 1.96 sigma.
std::optional<PairedComparison> Paired(double a, const metrics::Replicates& ra, double b,
                                       const metrics::Replicates& rb, double sigma) {
  const auto ci = metrics::PairedDifference(a, ra, b, rb);
  if (!ci) return std::nullopt;
  PairedComparison out;
  out.difference = a - b;
  const double noise_sigma = std::isnan(sigma) ? 0.0 : sigma;
  const metrics::Interval widened = metrics::WidenedInQuadrature(out.difference, *ci, noise_sigma);
  out.ci.lo = widened.lo;
  out.ci.hi = widened.hi;
  const double noise = metrics::kZ95 * noise_sigma;
  const double half = 0.5 * (out.ci.hi - out.ci.lo);
  out.noise_share = half > 0 ? noise / half : (noise > 0 ? 1.0 : 0.0);
  return out;
}

}  // namespace

std::optional<PairedComparison> PairedTvErr(const Evidence& a, const Evidence& b) {
  if (!Pair(a, b) || std::isnan(a.tv_err) || std::isnan(b.tv_err)) return std::nullopt;
  // Both rows were measured against one reference: its noise (a's and b's
  // ref_noise are the same F) cancels but for the cross term.
  const double noise = std::isnan(a.ref_noise) ? 0.0 : a.ref_noise;
  const double sigma = metrics::PairedNoiseSigma(noise, a.tv_test, b.tv_test, a.frames, a.pixels);
  return Paired(a.tv_err, a.draws->tv_err, b.tv_err, b.draws->tv_err, sigma);
}

std::optional<PairedComparison> PairedJoint(const Evidence& a, const Evidence& b) {
  if (!Pair(a, b) || std::isnan(a.joint) || std::isnan(b.joint)) return std::nullopt;
  const double sigma = (std::isnan(a.joint_noise_sigma) ? 0.0 : a.joint_noise_sigma) +
                       (std::isnan(b.joint_noise_sigma) ? 0.0 : b.joint_noise_sigma);
  return Paired(a.joint, a.draws->relmse, b.joint, b.draws->relmse, sigma);
}

namespace {

// NoiseShare with the pair already compared (or not pairing: nullopt).
double ShareOf(const Evidence& a, const Evidence& b, const std::optional<PairedComparison>& paired) {
  if (paired) return paired->noise_share;
  if (std::isnan(a.noise_share) && std::isnan(b.noise_share)) return kNaN;
  return std::max(std::isnan(a.noise_share) ? 0.0 : a.noise_share, std::isnan(b.noise_share) ? 0.0 : b.noise_share);
}

// NoiseBelowVisibility with the share already known.
bool BelowVisibility(const Evidence& v, const Evidence& none, double share) {
  if (!(share > kNoiseShareLimit)) return false;
  // Both rows share the reference; the larger contrast decides.
  const double contrast = std::max(v.noise_contrast, none.noise_contrast);
  return contrast < kVisibleContrast;  // false when either is unknown (NaN)
}

}  // namespace

double NoiseShare(const Evidence& a, const Evidence& b) { return ShareOf(a, b, PairedTvErr(a, b)); }

Verdict SeparatePaired(const PairedComparison& d) {
  if (!(d.ci.lo == d.ci.lo) || !(d.ci.hi == d.ci.hi)) return Verdict::kUnknown;
  if (d.ci.hi < 0) return Verdict::kBetter;
  if (d.ci.lo > 0) return Verdict::kWorse;
  return Verdict::kIndistinguishable;
}

Verdict Separate(Interval a, Interval b) {
  if (!a.Known() || !b.Known()) return Verdict::kUnknown;
  if (a.hi < b.lo) return Verdict::kBetter;
  if (b.hi < a.lo) return Verdict::kWorse;
  return Verdict::kIndistinguishable;
}

Outcome Decide(const Evidence& v, const Evidence& none) {
  if (!v.tv_err_ci.Known() || !none.tv_err_ci.Known()) return Outcome::kUnknown;
  if (v.smooth_limit) return Outcome::kSmoothLimit;
  if (Near(v.tv_err, none.tv_err) && (std::isnan(v.joint) || Near(v.joint, none.joint))) return Outcome::kNoEffect;
  const std::optional<PairedComparison> paired = PairedTvErr(v, none);
  switch (paired ? SeparatePaired(*paired) : Separate(v.tv_err_ci, none.tv_err_ci)) {
    case Verdict::kBetter: {
      // On a glint material each model draws a microstructure of its own
      // and `none` the reference's: their spatial errors measure that
      // difference, not blur (an independent draw of the same law has about
      // twice the smooth limit's), and the sparkle test takes the blur
      // test's place.
      const bool blurrier = !v.glint && v.spatial_ci.Known() && none.spatial_ci.Known() &&
                            v.spatial_ci.lo > kSpatialTolerance * none.spatial_ci.hi;
      if (blurrier) return Outcome::kBlurrier;
      if (!Meets(v.energy_ci, v.energy_bias)) return Outcome::kLosesEnergy;
      if (!KeepsGlints(v)) return Outcome::kLosesGlints;
      return Outcome::kBetter;
    }
    case Verdict::kWorse: return Outcome::kLessSteady;
    default: break;
  }
  // The pair is compared once: its noise share decides a tie too.
  const double share = ShareOf(v, none, paired);
  if (share > kNoiseShareLimit && !BelowVisibility(v, none, share)) return Outcome::kUnresolved;
  return Outcome::kTied;
}

bool NoiseBelowVisibility(const Evidence& v, const Evidence& none) {
  return BelowVisibility(v, none, NoiseShare(v, none));
}

std::string OutcomeText(Outcome outcome) {
  switch (outcome) {
    case Outcome::kBetter: return "**better**";
    case Outcome::kTied: return "≈ none";
    case Outcome::kNoEffect: return "no effect";
    case Outcome::kBlurrier: return "steadier, blurrier";
    case Outcome::kLosesEnergy: return "steadier, loses energy";
    case Outcome::kLosesGlints: return "steadier, loses the glints";
    case Outcome::kSmoothLimit: return "smooth limit (no glints)";
    case Outcome::kLessSteady: return "less steady";
    case Outcome::kUnresolved: return "unresolved: reference noise";
    case Outcome::kBaseline: return "baseline";
    case Outcome::kUnknown: break;
  }
  return "n/a (no intervals)";
}

std::string DecisionRuleText() {
  return "A variant is **better** than `none` in a table when (1) it is steadier: the 95 % interval of its `tv_err` "
         "minus `none`'s lies below 0 (paired: both rows were measured on the same bootstrap draws against the "
         "same reference, so the reference's noise, common to both, cancels but for a cross term that widens "
         "the interval; rows without paired draws compare their own intervals, and it must lie wholly below "
         "`none`'s); (2) it does not blur beyond tolerance: the lower end of its spatial error "
         "(`relmse_spatial`) interval is at most " +
         FormatNumber(kSpatialTolerance, "%g") +
         "× the upper end of `none`'s (else **steadier, blurrier**; not on a glint material, where each model "
         "draws a microstructure of its own and `none` the reference's, so that the spatial error measures "
         "that difference and not blur, and test (4) takes its place); and (3) it keeps the highlight: its "
         "`energy_bias` interval meets ±" +
         FormatNumber(kEnergyTolerance, "%.2f") +
         " (else **steadier, loses energy**); on a glint material (4) its sparkles per frame and their "
         "lifetime lie between 1/" +
         FormatNumber(kSparkleTolerance, "%g") + " and " + FormatNumber(kSparkleTolerance, "%g") +
         "× the reference's and the count's variance over frames between 1/" +
         FormatNumber(kSparkleTolerance * kSparkleTolerance, "%g") + " and " +
         FormatNumber(kSparkleTolerance * kSparkleTolerance, "%g") +
         "× (else **steadier, loses the glints**); the glint material's limit without sparkles (`glints-smooth`, "
         "D_g) is the **smooth limit**, a bound and never a pick. A variant within " + FormatNumber(100 * kNilEffect, "%g") +
         " % of `none` in both `tv_err` and the joint error has **no effect**; one whose difference interval holds 0 "
         "is **≈ none**, or **unresolved: reference noise** when the reference's noise is over " +
         FormatNumber(100 * kNoiseShareLimit, "%g") +
         " % of that interval's half-width (unpaired: of either row's `tv_err`) and its contrast (√`ref_noise` / `ref_mean`) is not below " +
         FormatNumber(100 * kVisibleContrast, "%g") +
         " % (fainter noise hides no visible flicker, and the tie stands); one wholly above is **less steady**. A cell's **pick** is, among the "
         "filters better than `none` in at least " +
         FormatNumber(100 * kPickShare, "%g") +
         " % of the cell's tables and of no effect in at most half, the one with the lowest median joint error "
         "(`relmse`) ratio to `none`; without one the answer is **keep `none`**. `supersample-N` is the "
         "brute-force baseline (N² shading per pixel) and never a pick. The pick and the runner-up are **tied** "
         "unless the interval of the pick's joint error minus the runner-up's (paired as above) lies below 0 in at "
         "least half of their shared tables and above it in none. Two values whose intervals overlap are never ranked.";
}

std::string CellRowOf(const Group& group) {
  if (IsGlintMaterial(group.material)) return "glints";
  // One read of the traits (a row stored before they were kept loads its scene file for them).
  const SceneTraits traits = group.rows.empty() ? SceneTraits{} : TraitsOf(*group.rows.front());
  if (!traits.geometry_class.empty()) return traits.geometry_class;
  if (traits.sg_light) return "SG-lit";
  if (traits.normal_maps) return "normal-mapped";
  if (traits.meshes) return "mesh";
  return GeometryClass(group.scene);
}

std::vector<std::string> CellRowsInOrder(const std::set<std::string>& rows) {
  std::vector<std::string> out;
  for (const std::string& row : kRows) {
    if (row == "other")
      for (const std::string& declared : rows)
        if (std::find(kRows.begin(), kRows.end(), declared) == kRows.end()) out.push_back(declared);
    if (rows.count(row)) out.push_back(row);
  }
  return out;
}
const std::vector<std::string>& RoughnessBands() { return kBands; }

bool CellCandidate::Eligible(int cell_tables) const {
  return !supersample && cell_tables > 0 && better >= kPickShare * cell_tables && 2 * no_effect <= tables;
}

std::vector<CellCandidate> Candidates(const std::vector<const Group*>& groups) {
  std::map<std::string, CellCandidate> by_label;
  for (const Group* g : groups) {
    const JobResult* none = NoneOf(*g);
    if (!none) continue;
    for (const JobResult* r : g->rows) {
      if (r == none || r->job.variant == "none") continue;
      CellCandidate& c = by_label[Label(*r)];
      c.label = Label(*r);
      c.supersample = IsSupersample(*r);
      c.rows.push_back({g, r});
    }
  }
  const int tables = int(groups.size());
  std::vector<CellCandidate> out;
  for (auto& [label, c] : by_label) {
    std::vector<double> joint, tv, bias;
    std::map<std::string, std::vector<double>> cost;
    for (const auto& [g, r] : c.rows) {
      const Evidence e = EvidenceOf(*r), base = EvidenceOf(*NoneOf(*g));
      ++c.tables;
      switch (Decide(e, base)) {
        case Outcome::kBetter: ++c.better; break;
        case Outcome::kNoEffect: ++c.no_effect; break;
        case Outcome::kUnresolved: ++c.unresolved; break;
        default: break;
      }
      c.energy_within += Meets(e.energy_ci, e.energy_bias);
      joint.push_back(base.joint > 0 ? e.joint / base.joint : kNaN);
      tv.push_back(base.tv_err > 0 ? e.tv_err / base.tv_err : kNaN);
      bias.push_back(e.energy_bias);
      if (r->cost) cost[r->cost->device].push_back(r->cost->ratio_to_none);
    }
    c.share = tables ? double(c.better) / tables : kNaN;
    c.joint_ratio = QuartilesOf(joint), c.tv_err_ratio = QuartilesOf(tv), c.energy_bias = QuartilesOf(bias);
    for (const auto& [device, values] : cost) c.cost[device] = QuartilesOf(values);
    out.push_back(std::move(c));
  }
  auto median_before = [](const Quartiles& a, const Quartiles& b) {
    if (std::isnan(a.median) != std::isnan(b.median)) return !std::isnan(a.median);
    return a.median < b.median;
  };
  std::sort(out.begin(), out.end(), [&](const CellCandidate& a, const CellCandidate& b) {
    const bool ea = a.Eligible(tables), eb = b.Eligible(tables);
    if (ea != eb) return ea;
    if (ea && a.joint_ratio.median != b.joint_ratio.median) return median_before(a.joint_ratio, b.joint_ratio);
    if (a.better != b.better) return a.better > b.better;
    if (a.joint_ratio.median != b.joint_ratio.median) return median_before(a.joint_ratio, b.joint_ratio);
    return a.label < b.label;
  });
  return out;
}

std::vector<CellAnswer> AnswerCells(const std::vector<const Group*>& groups) {
  std::map<std::pair<int, int>, std::vector<const Group*>> cells;
  auto index = [](const std::vector<std::string>& order, const std::string& name) {
    return int(std::find(order.begin(), order.end(), name) - order.begin());
  };
  std::vector<std::string> row_of;
  for (const Group* g : groups) row_of.push_back(CellRowOf(*g));
  const std::vector<std::string> rows = CellRowsInOrder({row_of.begin(), row_of.end()});
  for (std::size_t i = 0; i < groups.size(); ++i)
    cells[{index(rows, row_of[i]), index(kBands, RoughnessClass(groups[i]->alpha))}].push_back(groups[i]);

  std::vector<CellAnswer> out;
  for (const auto& [key, members] : cells) {
    CellAnswer cell;
    cell.row = rows[key.first], cell.band = kBands[key.second];
    cell.tables = int(members.size());
    std::set<std::string> shots;
    for (const Group* g : members) shots.insert(g->Shot());
    cell.shots = int(shots.size());
    cell.candidates = Candidates(members);
    const int tables = cell.tables;
    if (!cell.candidates.empty() && cell.candidates[0].Eligible(tables)) cell.pick = &cell.candidates[0];
    if (cell.pick && cell.candidates.size() > 1 && cell.candidates[1].Eligible(tables))
      cell.runner_up = &cell.candidates[1];
    if (cell.runner_up) {
      std::map<const Group*, const JobResult*> other;
      for (const auto& [g, r] : cell.runner_up->rows) other[g] = r;
      for (const auto& [g, r] : cell.pick->rows) {
        auto it = other.find(g);
        if (it == other.end()) continue;
        const Evidence a = EvidenceOf(*r), b = EvidenceOf(*it->second);
        const std::optional<PairedComparison> paired = PairedJoint(a, b);
        switch (paired ? SeparatePaired(*paired) : Separate(a.joint_ci, b.joint_ci)) {
          case Verdict::kBetter: ++cell.ahead; break;
          case Verdict::kWorse: ++cell.behind; break;
          default: ++cell.tied; break;
        }
      }
      const int shared = cell.ahead + cell.behind + cell.tied;
      cell.pick_ahead = shared > 0 && cell.behind == 0 && 2 * cell.ahead >= shared;
    }
    out.push_back(std::move(cell));
  }
  return out;
}

}  // namespace shimmer::experiments::report
