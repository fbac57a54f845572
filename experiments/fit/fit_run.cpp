#include "shimmer/experiments/fit_run.h"

#include <cmath>
#include <map>
#include <set>

#include "shimmer/experiments/output_files.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/renderer/scene.h"

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

struct Objective {
  const Spec& spec;
  const FitConfig& config;
  const std::string& material;
  const std::string& variant;
  const std::string& map;  // "" : each scene's own
  CachedMeasure& measure;
  std::set<std::string>* used;  // ids of every job this fit consulted

  // NaN when a render or measurement failed (measure.error() says why).
  ObjectiveValue operator()(double p, const ShotSet& shots) const {
    ObjectiveValue value;
    for (const std::string& shot_scene : shots.scenes)
      for (const std::string& camera : shots.cameras) {
        const std::string scene = MappedScene(shot_scene, map);
        const Job none_job = SpecJob(spec, scene, material, camera, "none", {}, config.derivatives);
        const Job test_job = SpecJob(spec, scene, material, camera, variant, {{config.param, p}}, config.derivatives);
        const std::string none_id = JobId(none_job), test_id = JobId(test_job);
        used->insert(none_id);
        used->insert(test_id);
        const nlohmann::json* none = measure.Metrics(none_job, none_id);
        const nlohmann::json* test = measure.Metrics(test_job, test_id);
        if (!none || !test) return {std::nan(""), {}};
        ShotTerms t;
        t.scene = scene;
        t.camera = camera;
        t.flicker = FlickerIndex(*test);
        t.flicker_none = FlickerIndex(*none);
        t.relmse = Metric(*test, "relmse");
        t.relmse_none = Metric(*none, "relmse");
        t.bias = Metric(*test, "energy_bias");
        t.j = ShotObjective(config.weights, t);
        value.shots.push_back(t);
        value.j += t.j;
      }
    value.j /= double(value.shots.size());
    return value;
  }
};

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
  return {{"j", v.j}, {"shots", shots}};
}

}  // namespace

double ShotObjective(const FitWeights& w, const ShotTerms& t) {
  return w.flicker * Ratio(t.flicker, t.flicker_none) + w.spatial * Ratio(t.relmse, t.relmse_none) +
         w.bias * t.bias * t.bias;
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

  // value(alpha) per (variant, param, NDF, map), across materials.
  std::map<std::tuple<std::string, std::string, std::string, std::string>, FitLaw> laws;
  for (const MaterialFit& f : outcome.fits) {
    FitLaw& law = laws[{f.variant, f.param, f.ndf, f.map}];
    law.variant = f.variant;
    law.param = f.param;
    law.ndf = f.ndf;
    law.map = f.map;
    law.materials.push_back(f.material);
    law.alpha.push_back(f.alpha);
    law.value.push_back(f.search.best);
  }
  for (auto& [key, law] : laws) {
    if (std::set<double>(law.alpha.begin(), law.alpha.end()).size() < 2) continue;  // a curve needs two alphas
    law.law = FitPowerLaw(law.alpha, law.value);
    outcome.laws.push_back(std::move(law));
  }
  return outcome;
}

}  // namespace shimmer::experiments
