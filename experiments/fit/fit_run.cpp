#include "shimmer/experiments/fit_run.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <set>

#include "shimmer/experiments/output_files.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/renderer/scene.h"
#include "shimmer/shading/shading.h"
#include "shimmer/shading/user_variant.h"

namespace shimmer::experiments {

namespace {

double Ratio(double value, double none) {
  if (none > 0) return value / none;
  return value;  // nothing to normalise by: the unfiltered shot has no such error
}

// Measures jobs through the store: a job measured before (this run or an
// earlier one) is read back, not rendered.
class CachedMeasure {
 public:
  CachedMeasure(ResultStore* store, const RunOptions& options, const std::function<void(const std::string&)>& progress)
      : store_(store), options_(options), progress_(progress) {}

  const nlohmann::json* Metrics(const Job& job, const std::string& id) {
    if (error_) return nullptr;  // the fit stops at its first failure
    if (auto it = cache_.find(id); it != cache_.end()) return &it->second;
    auto row = store_->Get(id);
    if (!row) {
      error_ = row.failure();
      return nullptr;
    }
    if (*row) {
      wall_s_[id] = (*row)->wall_s;
      return &(cache_[id] = (*row)->metrics);
    }
    if (progress_) {
      std::string what = "rendering " + job.scene + " " + job.camera + " " + job.variant;
      for (const auto& [k, v] : job.params) what += " " + k + "=" + FormatNumber(v);
      progress_(what);
    }
    auto measured = MeasureJob(job, options_);
    Status stored = measured ? store_->Insert(*measured) : Status(measured.failure());
    if (!stored) {
      error_ = stored.failure();
      return nullptr;
    }
    ++rendered_;
    wall_s_[id] = measured->wall_s;
    return &(cache_[id] = measured->metrics);
  }
  // Render-and-measure seconds of a job, as recorded when it was computed.
  double WallSeconds(const std::string& id) const {
    auto it = wall_s_.find(id);
    return it == wall_s_.end() ? 0.0 : it->second;
  }
  const std::optional<Error>& error() const { return error_; }
  int rendered() const { return rendered_; }

 private:
  ResultStore* store_;
  const RunOptions& options_;
  const std::function<void(const std::string&)>& progress_;
  std::map<std::string, nlohmann::json> cache_;
  std::map<std::string, double> wall_s_;
  std::optional<Error> error_;
  int rendered_ = 0;
};

// Half the width of a metric's 95 % interval (0 when the row has none).
double HalfWidth(const nlohmann::json& metrics, const char* key) {
  const auto ci = MetricCi95(metrics, key);
  return ci ? 0.5 * (ci->second - ci->first) : 0;
}

struct Objective {
  const Spec& spec;
  const FitConfig& config;
  const std::string& material;
  const std::string& variant;
  const std::string& map;  // "" : each scene's own
  CachedMeasure& measure;
  std::set<std::string>* used;  // ids of every job this fit consulted

  // NaN when a render or measurement failed (measure.error() says why).
  ObjectiveValue operator()(double p, const ShotSet& shots) const { return (*this)({{config.param, p}}, shots); }

  ObjectiveValue operator()(const std::map<std::string, double>& params, const ShotSet& shots) const {
    ObjectiveValue value;
    for (const std::string& shot_scene : shots.scenes)
      for (const std::string& camera : shots.cameras) {
        const std::string scene = MappedScene(shot_scene, map);
        const Job none_job = SpecJob(spec, scene, material, camera, "none", {}, config.derivatives);
        const Job test_job = SpecJob(spec, scene, material, camera, variant, params, config.derivatives);
        const std::string none_id = JobId(none_job), test_id = JobId(test_job);
        used->insert(none_id);
        used->insert(test_id);
        const nlohmann::json* none = measure.Metrics(none_job, none_id);
        const nlohmann::json* test = measure.Metrics(test_job, test_id);
        if (!none || !test) return {std::nan(""), 0, {}};
        ShotTerms t;
        t.scene = scene;
        t.camera = camera;
        t.flicker = FlickerIndex(*test);
        t.flicker_none = FlickerIndex(*none);
        t.relmse = Metric(*test, "relmse");
        t.relmse_none = Metric(*none, "relmse");
        t.bias = Metric(*test, "energy_bias");
        t.flicker_hw = HalfWidth(*test, "flicker_index");
        t.relmse_hw = HalfWidth(*test, "relmse");
        t.bias_hw = HalfWidth(*test, "energy_bias");
        t.j = ShotObjective(config.weights, t);
        value.shots.push_back(t);
        value.j += t.j;
      }
    value.j /= double(value.shots.size());
    value.half_width = ObjectiveHalfWidth(config.weights, value.shots);
    return value;
  }
};


// A variant's own values of `names`: its catalogue defaults, or those its
// user file declares (the spec checked that it has every one).
std::vector<double> OwnSetting(const Spec& spec, const std::string& variant, const std::vector<std::string>& names) {
  std::vector<double> values;
  if (auto it = spec.user_variants.find(variant); it != spec.user_variants.end()) {
    for (const std::string& n : names) values.push_back(shading::FindUserParam(*it->second, n)->default_value);
    return values;
  }
  const shading::Params<double> p = shading::ResolveParams(*shading::FindVariant(variant), {}).value();
  for (const std::string& n : names) values.push_back(shading::ParamValue(p, n));
  return values;
}

std::map<std::string, double> Setting(const std::vector<std::string>& names, const std::vector<double>& values) {
  std::map<std::string, double> m;
  for (std::size_t i = 0; i < names.size(); ++i) m[names[i]] = values[i];
  return m;
}

nlohmann::json ToJson(const ObjectiveValue& v) {
  nlohmann::json shots = nlohmann::json::array();
  for (const ShotTerms& t : v.shots)
    shots.push_back({{"scene", t.scene},
                     {"camera", t.camera},
                     {"flicker_index", t.flicker},
                     {"flicker_index_none", t.flicker_none},
                     {"relmse", t.relmse},
                     {"relmse_none", t.relmse_none},
                     {"energy_bias", t.bias},
                     {"j", t.j}});
  return {{"j", v.j}, {"j_ci95_half_width", v.half_width}, {"shots", shots}};
}

ObjectiveValue ObjectiveFromJson(const nlohmann::json& j) {
  ObjectiveValue v;
  v.j = j.at("j").get<double>();
  v.half_width = j.at("j_ci95_half_width").get<double>();
  for (const nlohmann::json& t : j.value("shots", nlohmann::json::array())) {
    ShotTerms s;
    s.scene = t.at("scene").get<std::string>(), s.camera = t.at("camera").get<std::string>();
    s.flicker = t.at("flicker_index").get<double>(), s.flicker_none = t.at("flicker_index_none").get<double>();
    s.relmse = t.at("relmse").get<double>(), s.relmse_none = t.at("relmse_none").get<double>();
    s.bias = t.at("energy_bias").get<double>(), s.j = t.at("j").get<double>();
    v.shots.push_back(std::move(s));
  }
  return v;
}

}  // namespace

double ShotObjective(const FitWeights& w, const ShotTerms& t) {
  return w.flicker * Ratio(t.flicker, t.flicker_none) + w.spatial * Ratio(t.relmse, t.relmse_none) +
         w.bias * t.bias * t.bias;
}

double ObjectiveHalfWidth(const FitWeights& w, const std::vector<ShotTerms>& shots) {
  if (shots.empty()) return 0;
  double sum = 0;
  for (const ShotTerms& t : shots) {
    const double f = w.flicker * Ratio(t.flicker_hw, t.flicker_none);
    const double e = w.spatial * Ratio(t.relmse_hw, t.relmse_none);
    // d(b^2) = 2 |b| db, and at least db^2 where b is near 0.
    const double b = w.bias * std::max(2 * std::abs(t.bias) * t.bias_hw, t.bias_hw * t.bias_hw);
    sum += f * f + e * e + b * b;
  }
  return std::sqrt(sum) / double(shots.size());
}

nlohmann::json MaterialFit::ToJson() const {
  nlohmann::json samples = nlohmann::json::array();
  for (const auto& [p, j] : search.samples) samples.push_back({p, j});
  nlohmann::json defaults_json = nlohmann::json::array();
  for (std::size_t i = 0; i < defaults.size(); ++i)
    defaults_json.push_back({{"value", defaults[i]},
                             {"train", experiments::ToJson(train_defaults[i])},
                             {"validate", experiments::ToJson(validate_defaults[i])}});
  nlohmann::json j = {{"variant", variant},
                      {"param", param},
                      {"material", material},
                      {"ndf", ndf},
                      {"alpha", alpha},
                      {"bounds", {lo, hi}},
                      {"value", search.best},
                      {"evaluations", search.evaluations},
                      {"ceres_improved", search.ceres_improved},
                      {"seconds", seconds},
                      {"samples", samples},
                      {"train", experiments::ToJson(train)},
                      {"validate", experiments::ToJson(validate)},
                      {"defaults", defaults_json}};
  if (!map.empty()) j["map"] = map;  // fits not per map keep their JSON as it was
  return j;
}

MaterialFit MaterialFit::FromJson(const nlohmann::json& j) {
  MaterialFit f;
  f.variant = j.at("variant").get<std::string>(), f.param = j.at("param").get<std::string>();
  f.material = j.at("material").get<std::string>(), f.ndf = j.at("ndf").get<std::string>();
  f.map = j.value("map", std::string());
  f.alpha = j.at("alpha").get<double>();
  f.lo = j.at("bounds").at(0).get<double>(), f.hi = j.at("bounds").at(1).get<double>();
  f.search.best = j.at("value").get<double>();
  f.search.evaluations = j.at("evaluations").get<int>();
  f.search.ceres_improved = j.at("ceres_improved").get<bool>();
  for (const nlohmann::json& s : j.at("samples")) f.search.samples.push_back({s.at(0).get<double>(), s.at(1).get<double>()});
  f.seconds = j.at("seconds").get<double>();
  f.train = ObjectiveFromJson(j.at("train"));
  f.validate = ObjectiveFromJson(j.at("validate"));
  for (const nlohmann::json& d : j.at("defaults")) {
    f.defaults.push_back(d.at("value").get<double>());
    f.train_defaults.push_back(ObjectiveFromJson(d.at("train")));
    f.validate_defaults.push_back(ObjectiveFromJson(d.at("validate")));
  }
  return f;
}

JointFit JointFit::FromJson(const nlohmann::json& j) {
  JointFit f;
  f.variant = j.at("variant").get<std::string>(), f.material = j.at("material").get<std::string>();
  f.ndf = j.at("ndf").get<std::string>();
  f.alpha = j.at("alpha").get<double>();
  f.params = j.at("params").get<std::vector<std::string>>();
  for (const nlohmann::json& b : j.value("bounds", nlohmann::json::array()))
    f.bounds.push_back({b.at(0).get<double>(), b.at(1).get<double>()});
  f.search.best = j.at("values").get<std::vector<double>>();
  f.search.evaluations = j.value("evaluations", 0);
  f.search.ceres_improved = j.value("ceres_improved", false);
  for (const nlohmann::json& s : j.value("samples", nlohmann::json::array()))
    f.search.samples.push_back({s.at(0).get<std::vector<double>>(), s.at(1).get<double>()});
  f.seconds = j.value("seconds", 0.0);
  f.train = ObjectiveFromJson(j.at("train"));
  f.validate = ObjectiveFromJson(j.at("validate"));
  const nlohmann::json& d = j.at("defaults");
  f.defaults = d.at("values").get<std::vector<double>>();
  f.train_defaults = ObjectiveFromJson(d.at("train"));
  f.validate_defaults = ObjectiveFromJson(d.at("validate"));
  for (const nlohmann::json& fj : j.value("folds", nlohmann::json::array())) {
    CrossFold fold;
    fold.scene = fj.at("scene").get<std::string>();
    fold.leave_out = fj.at("leave_out").get<bool>();
    fold.values = fj.at("values").get<std::vector<double>>();
    fold.held_out = ObjectiveFromJson(fj.at("held_out"));
    fold.held_out_defaults = ObjectiveFromJson(fj.at("held_out_defaults"));
    f.folds.push_back(std::move(fold));
  }
  return f;
}

nlohmann::json JointFit::ToJson() const {
  nlohmann::json samples = nlohmann::json::array();
  for (const auto& [p, j] : search.samples) samples.push_back({p, j});
  nlohmann::json bounds_json = nlohmann::json::array();
  for (const FitAxis& a : bounds) bounds_json.push_back({a.lo, a.hi});
  nlohmann::json folds_json = nlohmann::json::array();
  for (const CrossFold& f : folds)
    folds_json.push_back({{"scene", f.scene},
                          {"leave_out", f.leave_out},
                          {"values", f.values},
                          {"held_out", experiments::ToJson(f.held_out)},
                          {"held_out_defaults", experiments::ToJson(f.held_out_defaults)}});
  return {{"variant", variant},
          {"params", params},
          {"material", material},
          {"ndf", ndf},
          {"alpha", alpha},
          {"bounds", bounds_json},
          {"values", search.best},
          {"evaluations", search.evaluations},
          {"ceres_improved", search.ceres_improved},
          {"seconds", seconds},
          {"samples", samples},
          {"train", experiments::ToJson(train)},
          {"validate", experiments::ToJson(validate)},
          {"defaults", {{"values", defaults},
                        {"train", experiments::ToJson(train_defaults)},
                        {"validate", experiments::ToJson(validate_defaults)}}},
          {"folds", folds_json}};
}

namespace {

std::string SettingText(const std::vector<std::string>& names, const std::vector<double>& values) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i)
    text += (i ? "," : "") + names[i] + "=" + FormatNumber(values[i], "%.4g");
  return text;
}

// One joint fit of `variant` on `material`, with its cross-validation folds.
std::optional<Error> RunJointFit(const Spec& spec, const FitConfig& config, const std::string& variant,
                                 const std::string& material, CachedMeasure& measure, ResultStore& store,
                                 const std::function<void(const std::string&)>& log, FitOutcome* outcome) {
  const shading::MaterialDesc desc = *scene::ParseMaterial(material, {});
  std::set<std::string> used;
  const std::string no_map;
  Objective objective{spec, config, material, variant, no_map, measure, &used};
  auto j_on = [&](const ShotSet& shots) {
    return [&, shots](const std::vector<double>& p) { return objective(Setting(config.joint_params, p), shots).j; };
  };
  JointFit fit;
  fit.variant = variant;
  fit.material = material;
  fit.ndf = std::string(shading::NdfName(desc.ndf));
  fit.alpha = std::sqrt(desc.alpha.x * desc.alpha.y);
  fit.params = config.joint_params;
  fit.bounds = config.joint_bounds;
  fit.defaults = OwnSetting(spec, variant, config.joint_params);
  const int rendered_before = measure.rendered();
  // The defaults are not offered to the search, as in one dimension.
  fit.search = MinimizeND(j_on(config.train), config.joint_bounds, config.sweep_points);
  const auto best = Setting(config.joint_params, fit.search.best), own = Setting(config.joint_params, fit.defaults);
  fit.train = objective(best, config.train);
  fit.validate = objective(best, config.validate);
  fit.train_defaults = objective(own, config.train);
  fit.validate_defaults = objective(own, config.validate);
  if (config.cross_validate)
    for (const std::string& scene : config.train.scenes) {
      ShotSet rest{{}, config.train.cameras}, alone{{scene}, config.train.cameras};
      for (const std::string& s : config.train.scenes)
        if (s != scene) rest.scenes.push_back(s);
      // Left out: fitted on the others, measured on it under the training cameras.
      CrossFold out;
      out.scene = scene;
      out.values = MinimizeND(j_on(rest), config.joint_bounds, config.sweep_points).best;
      out.held_out = objective(Setting(config.joint_params, out.values), alone);
      out.held_out_defaults = objective(own, alone);
      fit.folds.push_back(out);
      // Alone: fitted on it, measured on it under the validation cameras.
      CrossFold in;
      in.scene = scene;
      in.leave_out = false;
      in.values = MinimizeND(j_on(alone), config.joint_bounds, config.sweep_points).best;
      const ShotSet moved{{scene}, config.validate.cameras};
      in.held_out = objective(Setting(config.joint_params, in.values), moved);
      in.held_out_defaults = objective(own, moved);
      fit.folds.push_back(in);
    }
  if (measure.error()) return Prefixed(variant + " on " + material, *measure.error());
  for (const std::string& id : used) fit.seconds += measure.WallSeconds(id);
  std::string names;
  for (const std::string& n : config.joint_params) names += (names.empty() ? "" : ",") + n;
  if (Status s = store.InsertFit(variant, names, material, "", std::nan(""), fit.train.j, fit.validate.j, fit.ToJson());
      !s)
    return s.failure();
  if (log) {
    char line[512];
    std::snprintf(line, sizeof line,
                  "%s %s on %s: J_train %.4g (own setting %.4g), J_validate %.4g (own %.4g) (%d evaluations, %d "
                  "renders, %.0f s)",
                  variant.c_str(), SettingText(fit.params, fit.search.best).c_str(), material.c_str(), fit.train.j,
                  fit.train_defaults.j, fit.validate.j, fit.validate_defaults.j, fit.search.evaluations,
                  measure.rendered() - rendered_before, fit.seconds);
    log(line);
  }
  outcome->joint_fits.push_back(std::move(fit));
  return std::nullopt;
}

}  // namespace

FitOutcome RunFits(const Spec& spec, const RunOptions& options, const std::function<void(const std::string&)>& log,
                   const std::function<void(const std::string&)>& progress) {
  FitOutcome outcome;
  if (spec.fits.empty()) {
    outcome.error = Error{ErrorCode::kBadInput, "the spec has no \"fit\" section"};
    return outcome;
  }
  auto lock = StoreLock::Acquire(options.db_path);
  if (!lock) {
    outcome.error = lock.failure();
    return outcome;
  }
  auto opened = ResultStore::Open(options.db_path);
  if (!opened) {
    (*lock)->Discard();
    outcome.error = opened.failure();
    return outcome;
  }
  std::unique_ptr<ResultStore> store = std::move(*opened);
  CachedMeasure measure(store.get(), options, progress);
  for (const FitConfig& config : spec.fits) {
    if (config.IsJoint()) {
      for (const std::string& variant : config.variants)
        for (const std::string& material : spec.materials)
          if (auto e = RunJointFit(spec, config, variant, material, measure, *store, log, &outcome)) {
            outcome.error = *e;
            return outcome;
          }
      continue;
    }
    const std::vector<std::string> maps = config.maps.empty() ? std::vector<std::string>{""} : config.maps;
    for (const std::string& variant : config.variants)
      for (const std::string& map : maps)
      for (const std::string& material : spec.materials) {
        const shading::MaterialDesc desc = *scene::ParseMaterial(material, {});
        std::set<std::string> used;
        Objective objective{spec, config, material, variant, map, measure, &used};
        MaterialFit fit;
        fit.variant = variant;
        fit.param = config.param;
        fit.material = material;
        fit.map = map;
        fit.ndf = std::string(shading::NdfName(desc.ndf));
        fit.alpha = std::sqrt(desc.alpha.x * desc.alpha.y);
        fit.lo = config.lo;
        fit.hi = config.hi;
        fit.defaults = config.defaults;
        const int rendered_before = measure.rendered();
        // The defaults are not offered to the search: that they lose to the
        // fitted value is a finding, not a construction.
        // After a failure every J is NaN at no cost, so one check below suffices.
        fit.search = Minimize1D([&](double p) { return objective(p, config.train).j; }, config.lo, config.hi,
                                config.sweep_points);
        fit.train = objective(fit.search.best, config.train);
        fit.validate = objective(fit.search.best, config.validate);
        for (double d : config.defaults) {
          fit.train_defaults.push_back(objective(d, config.train));
          fit.validate_defaults.push_back(objective(d, config.validate));
        }
        if (measure.error()) {
          outcome.error = Prefixed(variant + " on " + material + (map.empty() ? "" : " with map " + map),
                                   *measure.error());
          return outcome;
        }
        // The cost of the evaluations as recorded when each was computed, so
        // a rerun served from the cache reports the same time.
        for (const std::string& id : used) fit.seconds += measure.WallSeconds(id);
        if (Status s = store->InsertFit(variant, config.param, material, map, fit.search.best, fit.train.j,
                                        fit.validate.j, fit.ToJson());
            !s) {
          outcome.error = s.failure();
          return outcome;
        }
        if (log) {
          char line[256];
          std::snprintf(line, sizeof line,
                        "%s %s=%.4g on %s%s%s: J_train %.4g, J_validate %.4g (%d evaluations, %d renders, %.0f s)",
                        variant.c_str(), config.param.c_str(), fit.search.best, material.c_str(),
                        map.empty() ? "" : " with map ", map.c_str(), fit.train.j,
                        fit.validate.j, fit.search.evaluations, measure.rendered() - rendered_before, fit.seconds);
          log(line);
        }
        outcome.fits.push_back(std::move(fit));
      }
  }

  outcome.laws = FitLaws(outcome.fits);
  return outcome;
}

std::vector<FitLaw> FitLaws(const std::vector<MaterialFit>& fits) {
  std::map<std::tuple<std::string, std::string, std::string, std::string>, FitLaw> laws;
  for (const MaterialFit& f : fits) {
    FitLaw& law = laws[{f.variant, f.param, f.ndf, f.map}];
    law.variant = f.variant;
    law.param = f.param;
    law.ndf = f.ndf;
    law.map = f.map;
    if (OnBound(f.search.best, {f.lo, f.hi}) != Bound::kInside) {
      law.on_bound.push_back(f.material);
      continue;
    }
    law.materials.push_back(f.material);
    law.alpha.push_back(f.alpha);
    law.value.push_back(f.search.best);
  }
  std::vector<FitLaw> out;
  for (auto& [key, law] : laws) {
    if (std::set<double>(law.alpha.begin(), law.alpha.end()).size() < 2) continue;  // a curve needs two alphas
    law.law = FitPowerLaw(law.alpha, law.value);
    out.push_back(std::move(law));
  }
  return out;
}

}  // namespace shimmer::experiments
