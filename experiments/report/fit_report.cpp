#include "shimmer/experiments/fit_report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>

#include "decision_rule.h"
#include "report_parts.h"
#include "shimmer/core/gnuplot.h"
#include "shimmer/core/json_file.h"
#include "shimmer/experiments/output_files.h"

namespace shimmer::experiments {

namespace fs = std::filesystem;

namespace {

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

std::string Shots(const ShotSet& s) { return "scenes " + Join(s.scenes) + " × cameras " + Join(s.cameras); }

// A fit's row name: its material, and its normal map when the fit is per map.
std::string Subject(const MaterialFit& f) { return f.map.empty() ? f.material : f.material + " with " + f.map; }

// What to type into the engine a variant stands for: its knobs under the
// engine's names and units (HDRP squares its threshold, so the knob is the
// root of kappa). Other variants show their parameters as they are.
struct Knob {
  std::string param, name;
  bool root = false;  // the engine's knob is sqrt(param)
};
std::pair<std::string, std::vector<Knob>> EngineKnobs(const std::string& variant) {
  if (variant == "vlachos15")
    return {"Unreal, normal curvature to roughness (Vlachos' clamp)",
            {{"curvature_scale", "scale S"}, {"curvature_bias", "bias B"}, {"curvature_exponent", "exponent E"}}};
  if (variant == "filament")
    return {"Filament",
            {{"sigma2", "specularAntiAliasingVariance"}, {"kappa", "specularAntiAliasingThreshold"}}};
  if (variant == "unity-hdrp")
    return {"Unity HDRP", {{"sigma2", "screen space variance"}, {"kappa", "threshold", true}}};
  if (variant == "godot")
    return {"Godot", {{"sigma2", "roughness_limiter_amount"}, {"kappa", "roughness_limiter_limit"}}};
  return {variant, {}};
}

// " (on its lower bound 0.25)" when `value` sits on a bound of `axis`: the
// search stopped there, and the true optimum may lie beyond it. `show`
// turns the bound into the unit the value is printed in.
std::string BoundNote(double value, const FitAxis& axis, const std::function<double(double)>& show = {}) {
  const Bound bound = OnBound(value, axis);
  if (bound == Bound::kInside) return "";
  const double at = bound == Bound::kLower ? axis.lo : axis.hi;
  return std::string(" (on its ") + (bound == Bound::kLower ? "lower" : "upper") + " bound " +
         FormatNumber(show ? show(at) : at) + ")";
}

std::string KnobText(const std::string& variant, const std::vector<std::string>& params,
                     const std::vector<double>& values, const std::vector<FitAxis>& bounds = {}) {
  const auto knobs = EngineKnobs(variant).second;
  std::string text;
  for (std::size_t i = 0; i < params.size(); ++i) {
    std::string name = params[i];
    bool root = false;
    for (const Knob& k : knobs)
      if (k.param == params[i]) name = k.name, root = k.root;
    const auto show = [root](double x) { return root ? std::sqrt(std::max(x, 0.0)) : x; };
    text += (i ? ", " : "") + name + " = " + FormatNumber(show(values[i]));
    if (i < bounds.size()) text += BoundNote(values[i], bounds[i], show);
  }
  return text;
}

std::string WithInterval(const ObjectiveValue& v) {
  return FormatNumber(v.j) + " ± " + FormatNumber(v.half_width, "%.2g");
}

// Whether a fitted setting's J beats the shipped one's beyond both intervals
// (the report's rule for rows: lower is better, intervals apart).
std::string Verdict(const ObjectiveValue& fitted, const ObjectiveValue& shipped) {
  const auto interval = [](const ObjectiveValue& v) {
    return report::Interval{v.j - v.half_width, v.j + v.half_width};
  };
  switch (report::Separate(interval(fitted), interval(shipped))) {
    case report::Verdict::kBetter:
      return "fitted better";
    case report::Verdict::kWorse:
      return "shipped better";
    default:
      return "tied (intervals overlap)";
  }
}

std::string EngineSettingsMarkdown(const std::vector<JointFit>& fits) {
  std::ostringstream md;
  md << "## Engine settings\n\n"
     << "Each engine's own knobs, fitted jointly per material on the training shots (the same J), beside the "
        "setting the engine ships. ± is half the width of J's 95 % interval, to first order from the metrics' "
        "intervals (the shots and terms taken as independent); a verdict needs the two intervals apart.\n\n";
  std::string material;
  for (const EngineSettingRow& r : EngineSettingRows(fits)) {
    if (r.material != material) {
      md << (material.empty() ? "" : "\n") << "### " << r.material << "\n\n"
         << "| engine (variant) | fitted: the values to type in | shipped | J train, fitted (shipped) | "
            "J validate, fitted (shipped) | held out |\n|---|---|---|---|---|---|\n";
      material = r.material;
    }
    md << "| " << r.engine << " | " << r.fitted << " | " << r.shipped << " | " << r.train << " | " << r.validate
       << " | " << r.held_out << " |\n";
  }
  md << "\n";
  bool any_folds = false;
  for (const JointFit& f : fits) any_folds |= !f.folds.empty();
  if (!any_folds) return md.str();
  md << "### Does a setting transfer?\n\n"
        "Per training scene (a geometry class): **left out**, the setting fitted on the other training scenes, "
        "measured on this one; **alone**, the setting fitted on this scene only, measured on it under the "
        "validation cameras. Each beside the shipped setting on the same shots.\n\n"
        "| variant | material | scene | left out: setting | J (shipped) | verdict | alone: setting | J (shipped) | "
        "verdict |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const JointFit& f : fits)
    for (std::size_t i = 0; i + 1 < f.folds.size(); i += 2) {
      const CrossFold& out = f.folds[i];
      const CrossFold& alone = f.folds[i + 1];
      md << "| `" << f.variant << "` | " << f.material << " | " << out.scene << " | "
         << KnobText(f.variant, f.params, out.values, f.bounds) << " | " << WithInterval(out.held_out) << " ("
         << WithInterval(out.held_out_defaults) << ") | " << Verdict(out.held_out, out.held_out_defaults) << " | "
         << KnobText(f.variant, f.params, alone.values, f.bounds) << " | " << WithInterval(alone.held_out) << " ("
         << WithInterval(alone.held_out_defaults) << ") | " << Verdict(alone.held_out, alone.held_out_defaults)
         << " |\n";
    }
  md << "\n";
  return md.str();
}

}  // namespace

std::vector<EngineSettingRow> EngineSettingRows(const std::vector<JointFit>& fits) {
  std::map<std::string, std::vector<const JointFit*>> by_material;
  for (const JointFit& f : fits) by_material[f.material].push_back(&f);
  std::vector<EngineSettingRow> rows;
  for (const auto& [material, list] : by_material)
    for (const JointFit* f : list)
      rows.push_back({material, EngineKnobs(f->variant).first + " (`" + f->variant + "`)",
                      KnobText(f->variant, f->params, f->search.best, f->bounds),
                      KnobText(f->variant, f->params, f->defaults),
                      WithInterval(f->train) + " (" + WithInterval(f->train_defaults) + ")",
                      WithInterval(f->validate) + " (" + WithInterval(f->validate_defaults) + ")",
                      Verdict(f->validate, f->validate_defaults)});
  return rows;
}

TransferCount CountTransfer(const std::vector<JointFit>& fits, bool leave_out) {
  TransferCount c;
  for (const JointFit& f : fits)
    for (const CrossFold& fold : f.folds) {
      if (fold.leave_out != leave_out) continue;
      const std::string v = Verdict(fold.held_out, fold.held_out_defaults);
      (v == "fitted better" ? c.fitted_better : v == "shipped better" ? c.shipped_better : c.within) += 1;
    }
  return c;
}

Result<FitOutcome> ReadFitOutcome(const std::string& path) {
  auto doc = ReadJsonFile(path);
  if (!doc) return doc.failure();
  auto fail = [&](const std::string& why) { return Result<FitOutcome>(Error{ErrorCode::kBadInput, path + ": " + why}); };
  try {
    if (!doc->is_object() || (!doc->contains("fits") && !doc->contains("joint_fits")))
      return fail("not a fit.json (neither \"fits\" nor \"joint_fits\"; shimmer fit writes one)");
    FitOutcome outcome;
    for (const nlohmann::json& j : doc->value("fits", nlohmann::json::array()))
      outcome.fits.push_back(MaterialFit::FromJson(j));
    for (const nlohmann::json& j : doc->value("joint_fits", nlohmann::json::array())) {
      JointFit f = JointFit::FromJson(j);
      if (f.search.best.size() != f.params.size() || f.defaults.size() != f.params.size())
        return fail("joint fit of " + f.variant + " on " + f.material + " has " +
                    std::to_string(f.search.best.size()) + " values for " + std::to_string(f.params.size()) +
                    " parameters");
      outcome.joint_fits.push_back(std::move(f));
    }
    outcome.laws = FitLaws(outcome.fits);
    return outcome;
  } catch (const nlohmann::json::exception& e) {
    return fail(std::string("not a fit.json as shimmer fit writes it: ") + e.what());
  }
}

Result<std::vector<JointFit>> ReadJointFits(const std::string& path) {
  auto outcome = ReadFitOutcome(path);
  if (!outcome) return outcome.failure();
  if (outcome->joint_fits.empty())
    return Result<std::vector<JointFit>>(
        Error{ErrorCode::kBadInput, path + ": has no joint fits (no \"joint_fits\" in it, or none; run shimmer fit "
                                           "on a spec with joint fits)"});
  return std::move(outcome->joint_fits);
}

namespace {

nlohmann::json FitJson(const FitOutcome& outcome, const Spec& spec) {
  nlohmann::json all = {{"spec", spec.name}, {"fits", nlohmann::json::array()}, {"laws", nlohmann::json::array()}};
  for (const MaterialFit& f : outcome.fits) all["fits"].push_back(f.ToJson());
  if (!outcome.joint_fits.empty()) {
    all["joint_fits"] = nlohmann::json::array();
    for (const JointFit& f : outcome.joint_fits) all["joint_fits"].push_back(f.ToJson());
  }
  for (const FitLaw& l : outcome.laws) {
    nlohmann::json law = {{"variant", l.variant},   {"param", l.param}, {"ndf", l.ndf},
                          {"a", l.law.a},           {"b", l.law.b},     {"materials", l.materials},
                          {"alpha", l.alpha},       {"value", l.value}, {"log_residuals", l.law.residuals},
                          {"on_bound", l.on_bound}};
    if (l.law.HasInterval())
      law["ci95"] = {{"a", {l.law.a_lo, l.law.a_hi}}, {"b", {l.law.b_lo, l.law.b_hi}}};
    if (!l.map.empty()) law["map"] = l.map;
    all["laws"].push_back(law);
  }
  return all;
}

// The objective, the frames and each fit's configuration.
std::string FitIntroMarkdown(const Spec& spec) {
  std::ostringstream md;
  md << "# Fitted filter parameters: " << spec.name << "\n\n"
     << "Generated by `shimmer fit`. Objective, averaged over a set of shots (scene × camera):\n\n"
     << "    J(p) = w_f · F(p) / F(none) + w_s · E(p) / E(none) + w_b · b(p)²\n\n"
     << "F is the `flicker_index` of the error sequence, E the spatial `relmse`, b the signed `energy_bias` "
        "(docs/metrics.md); F and E are divided by the unfiltered (`none`) render of the same shot, so J = w_f + "
        "w_s + (bias term) means \"no better than no filter\" on every material, and the weights compare like with "
        "like across materials. The search minimises J on the training shots: a log-spaced sweep, then Ceres "
        "(trust region on u = log p, within the bounds) from the sweep's best point with central differences of "
        "step 10 % in p: large against the objective's aliasing noise, which finer steps turn into meaningless "
        "slopes. The published defaults are not offered to the search; validation evaluates the fitted value and the "
        "defaults on held-out shots. Frames: "
     << spec.width << "×" << spec.height << ", " << spec.frames << " frames, reference " << spec.reference.spp << "×"
     << spec.reference.spp << " spp per replicate";
  // The fits' materials are the top level's; those only a group has are not fitted.
  for (const auto& [material, spp] : spec.reference_spp_by_material)
    if (std::find(spec.materials.begin(), spec.materials.end(), material) != spec.materials.end())
      md << ", " << spp << "×" << spp << " for " << material;
  md << " (" << spec.reference.replicates << " replicates).\n\n";

  for (const FitConfig& c : spec.fits) {
    if (c.IsJoint()) {
      md << "Joint fit of " << Join(c.joint_params) << " for " << Join(c.variants) << " in";
      for (std::size_t i = 0; i < c.joint_bounds.size(); ++i)
        md << (i ? " ×" : "") << " [" << c.joint_bounds[i].lo << ", " << c.joint_bounds[i].hi << "]";
      md << ", a grid of " << c.sweep_points << " per axis, derivatives " << c.derivatives << ", weights w_f = "
         << c.weights.flicker << ", w_s = " << c.weights.spatial << ", w_b = " << c.weights.bias
         << ". Training: " << Shots(c.train) << ". Validation: " << Shots(c.validate) << "."
         << (c.cross_validate ? " Cross-validated per training scene." : "") << "\n\n";
      continue;
    }
    md << "Fit of `" << c.param << "` for " << Join(c.variants) << " in [" << c.lo << ", " << c.hi << "], "
       << c.sweep_points << " sweep points, derivatives " << c.derivatives << ", weights w_f = " << c.weights.flicker
       << ", w_s = " << c.weights.spatial << ", w_b = " << c.weights.bias << ". Training: " << Shots(c.train)
       << ". Validation: " << Shots(c.validate) << "."
       << (c.maps.empty() ? "" : " Once per normal map, every shot's scene rendered with it in place of its own: " +
                                     Join(c.maps) + ".")
       << "\n\n";
  }

  return md.str();
}

// One variant's parameter: its table of fits (into md), the J(p) samples
// (data) and the gnuplot script that draws them (plot).
struct FitSection {
  std::string slug;
  std::ostringstream md, data, plot;
};

void FitTable(const std::vector<const MaterialFit*>& fits, FitSection* section) {
  std::ostringstream& md = section->md;
  const MaterialFit& first = *fits.front();
  const bool per_map = std::any_of(fits.begin(), fits.end(), [](const MaterialFit* f) { return !f->map.empty(); });
  const std::string& slug = section->slug;
  md << "## " << first.variant << ": " << first.param << "\n\n![J(p)](" << slug << ".svg)\n\n"
     << "J with ± half the width of its 95 % interval (first order from the metrics' intervals); a fitted value "
        "on a bound of the search says so.\n\n"
     << "| material |" << (per_map ? " map |" : "") << " α | fitted " << first.param << " | J train | J validate |";
  for (double d : first.defaults) md << " J train at " << d << " | J validate at " << d << " |";
  md << " evaluations | render s |\n|---|---|---|---|---|" << (per_map ? "---|" : "");
  for (std::size_t i = 0; i < first.defaults.size(); ++i) md << "---|---|";
  md << "---|---|\n";
  std::ostringstream& data = section->data;
  std::ostringstream& plot = section->plot;
  plot << "set terminal svg size 900,560 dynamic noenhanced\nset output '" << slug << ".svg'\n"
       << "set title '" << first.variant << ": training objective J(" << first.param << ")'\n"
       << "set xlabel '" << first.param << "'\nset ylabel 'J'\nset logscale x\nset key outside right font ',9'\n"
       << "plot ";
  int block = 0;
  for (const MaterialFit* f : fits) {
    md << "| " << f->material << " | " << (per_map ? f->map + " | " : "") << FormatNumber(f->alpha) << " | **"
       << FormatNumber(f->search.best) << "**" << BoundNote(f->search.best, {f->lo, f->hi}) << " | "
       << WithInterval(f->train) << " | " << WithInterval(f->validate) << " |";
    for (std::size_t i = 0; i < f->defaults.size(); ++i)
      md << " " << WithInterval(f->train_defaults[i]) << " | " << WithInterval(f->validate_defaults[i]) << " |";
    md << " " << f->search.evaluations << " | " << FormatNumber(f->seconds, "%.0f") << " |\n";
    auto samples = f->search.samples;
    std::sort(samples.begin(), samples.end());
    data << "# " << Subject(*f) << ": p J\n";
    for (const auto& [p, j] : samples) data << p << " " << j << "\n";
    data << "\n\n# " << Subject(*f) << " optimum\n" << f->search.best << " " << f->train.j << "\n\n\n";
    plot << (block ? ", \\\n     " : "") << "'" << slug << ".dat' index " << 2 * block
         << " using 1:2 with linespoints pt 7 ps 0.5 title '" << Subject(*f) << "', \\\n     '' index "
         << 2 * block + 1 << " using 1:2 with points pt 6 ps 2 lc 'black' "
         << (block ? "notitle" : "title 'optimum'");
    ++block;
  }
  plot << "\n";
  md << "\n";
}

// Honest verdicts: does the fitted value hold up on shots it never saw?
// By the report's rule: one J beats another only with the intervals apart.
std::string HeldOutVerdicts(const std::vector<const MaterialFit*>& fits) {
  std::ostringstream md;
  int tied = 0, compared = 0;
  for (const MaterialFit* f : fits)
    for (std::size_t i = 0; i < f->defaults.size(); ++i) {
      ++compared;
      const std::string verdict = Verdict(f->validate, f->validate_defaults[i]);
      if (verdict == "shipped better")
        md << "- On held-out shots, the fitted value for " << Subject(*f) << " (J " << WithInterval(f->validate)
           << ") loses to the default " << f->defaults[i] << " (J " << WithInterval(f->validate_defaults[i])
           << "): the intervals are apart.\n";
      else if (verdict == "fitted better")
        md << "- On held-out shots, the fitted value for " << Subject(*f) << " (J " << WithInterval(f->validate)
           << ") beats the default " << f->defaults[i] << " (J " << WithInterval(f->validate_defaults[i])
           << "): the intervals are apart.\n";
      else
        ++tied;
    }
  if (compared)
    md << "- " << tied << " of " << compared
       << " held-out comparisons with a default are tied: the two J intervals overlap, and neither value is "
          "better there.\n";
  int on_bound = 0;
  for (const MaterialFit* f : fits) on_bound += OnBound(f->search.best, {f->lo, f->hi}) != Bound::kInside;
  if (on_bound)
    md << "- " << on_bound << " of " << fits.size()
       << " fitted values sit on a bound of the search (marked in the table): J still fell toward it, and the "
          "optimum may lie beyond; widen the bounds to find it.\n";
  return md.str();
}

// The closed forms fitted across materials for one variant's parameter.
std::string LawsMarkdown(const std::vector<FitLaw>& laws, const MaterialFit& first) {
  std::ostringstream md;
  for (const FitLaw& l : laws) {
    if (l.variant != first.variant || l.param != first.param) continue;
    const std::string subject = l.ndf + " materials" + (l.map.empty() ? "" : " with " + l.map);
    const std::string left_out =
        l.on_bound.empty() ? "" : " Left out, their fitted value on a bound: " + Join(l.on_bound) + ".";
    if (!l.law.HasInterval()) {
      md << "\nNo closed form for " << subject << ": " << l.alpha.size()
         << " materials with a fitted value inside the bounds fit any two-coefficient law exactly, with no "
            "residual to judge it by (a law is printed from three)." << left_out << "\n";
      continue;
    }
    md << "\nClosed form for " << subject << " (Ceres, Cauchy loss 0.2 on log " << l.param << "): **" << l.param
       << "(α) = " << FormatNumber(l.law.a) << " · α^" << FormatNumber(l.law.b) << "**, a in ["
       << FormatNumber(l.law.a_lo) << ", " << FormatNumber(l.law.a_hi) << "], b in [" << FormatNumber(l.law.b_lo)
       << ", " << FormatNumber(l.law.b_hi) << "] (95 %, Student's t on " << l.alpha.size() - 2
       << " degrees of freedom)." << left_out << "\n\n"
       << "| material | α | fitted | closed form | log residual |\n|---|---|---|---|---|\n";
    for (std::size_t i = 0; i < l.alpha.size(); ++i)
      md << "| " << l.materials[i] << " | " << FormatNumber(l.alpha[i]) << " | " << FormatNumber(l.value[i]) << " | "
         << FormatNumber(l.law.a * std::pow(l.alpha[i], l.law.b)) << " | "
         << FormatNumber(l.law.residuals[i], "%+.3f") << " |\n";
  }
  return md.str();
}

}  // namespace

Status WriteFitReport(const FitOutcome& outcome, const Spec& spec, const std::string& out_dir,
                      std::vector<std::string>* warnings) {
  if (outcome.fits.empty() && outcome.joint_fits.empty()) return Status::Failure("no fits to report");
  auto staged = StagedDirectory::Create(out_dir);
  if (!staged) return staged.failure();
  StagedDirectory& out = **staged;
  if (Status s = out.Write("fit.json", FitJson(outcome, spec).dump(2) + "\n"); !s) return s;

  std::ostringstream md;
  md << FitIntroMarkdown(spec);
  std::vector<std::string> scripts;
  std::map<std::string, std::vector<const MaterialFit*>> by_variant;
  for (const MaterialFit& f : outcome.fits) by_variant[f.variant + " / " + f.param].push_back(&f);
  for (const auto& [key, fits] : by_variant) {
    const MaterialFit& first = *fits.front();
    FitSection section;
    section.slug = "fit_" + Slug(first.variant + "_" + first.param);
    FitTable(fits, &section);
    md << section.md.str() << HeldOutVerdicts(fits) << LawsMarkdown(outcome.laws, first) << "\n";
    if (Status s = out.Write(section.slug + ".dat", section.data.str()); !s) return s;
    if (Status s = out.Write(section.slug + ".gp", section.plot.str()); !s) return s;
    scripts.push_back(section.slug + ".gp");
  }
  for (const std::string& script : scripts)
    if (Status s = RunGnuplot(out.staging(), script); !s) {
      // gnuplot missing or failing costs the plots; a plot cut short (a full disk) fails the report.
      if (s.code() == ErrorCode::kIo) return out.Unstaged(s.failure());
      if (warnings) warnings->push_back(s.error());
    }
  if (!outcome.joint_fits.empty()) md << EngineSettingsMarkdown(outcome.joint_fits);
  if (Status s = out.Write("fit.md", md.str()); !s) return s;
  return out.Commit("fit.md");
}

}  // namespace shimmer::experiments
