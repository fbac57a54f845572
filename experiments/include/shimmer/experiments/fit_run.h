// The fitting stage on rendered objectives: for each material and variant of
// a spec's `fit` section, the parameter value minimising J on the training
// shots, validated on held-out shots against the published defaults, and a
// closed form value(alpha) per variant and NDF across materials.
//
// J(p) = mean over shots of  w_f F(p)/F(none) + w_s E(p)/E(none) + w_b b(p)^2
// with F the flicker_index of the error sequence, E the spatial relmse and b
// the signed energy_bias (already a fraction of the reference's energy). The
// first two are ratios to the unfiltered render of the same shot, so 1 means
// "as bad as doing nothing" on every material and scene, and the weights
// trade comparable numbers.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shimmer/experiments/minimize.h"
#include "shimmer/experiments/runner.h"
#include "shimmer/experiments/spec.h"

namespace shimmer::experiments {

// One shot's part of J, with its raw terms.
struct ShotTerms {
  std::string scene, camera;
  double flicker = 0, flicker_none = 0;
  double relmse = 0, relmse_none = 0;
  double bias = 0;
  double j = 0;
  // Half-widths of the variant's 95 % intervals (metrics "ci95").
  double flicker_hw = 0, relmse_hw = 0, bias_hw = 0;
};

// w_f F/F_none + w_s E/E_none + w_b b^2; a term whose `none` value is 0 counts
// 0 when the variant is 0 too and its raw value otherwise.
double ShotObjective(const FitWeights& w, const ShotTerms& t);

// The half-width of J's 95 % interval from its terms' intervals (first
// order, the terms and shots taken as independent; the `none` renders'
// own uncertainty is not carried): a guide to which differences in J mean
// something, not a test.
double ObjectiveHalfWidth(const FitWeights& w, const std::vector<ShotTerms>& shots);

struct ObjectiveValue {
  double j = 0;           // mean of the shots' j
  double half_width = 0;  // ObjectiveHalfWidth
  std::vector<ShotTerms> shots;
};

struct MaterialFit {
  std::string variant, param, material, ndf;
  std::string map;  // the normal map every shot rendered with (FitConfig::maps); "": each scene's own
  double alpha = 0;  // sqrt(alpha_x alpha_y)
  double lo = 0, hi = 0;
  Fit1D search;                    // every evaluation of J on the training shots
  double seconds = 0;              // render + measure time of every job it used (references included)
  ObjectiveValue train, validate;  // at the fitted value
  std::vector<double> defaults;
  std::vector<ObjectiveValue> train_defaults, validate_defaults;
  nlohmann::json ToJson() const;
  static MaterialFit FromJson(const nlohmann::json& j);  // throws nlohmann::json::exception
};

struct FitLaw {
  std::string variant, param, ndf, map;
  std::vector<std::string> materials;
  std::vector<double> alpha, value;
  PowerLaw law;
  // Materials left out of the law: their fitted value sits on a bound, where
  // the search stopped rather than found a minimum.
  std::vector<std::string> on_bound;
};

// value(alpha) per (variant, param, NDF, map) across the fits' materials,
// those on a bound left out; none where fewer than two alphas remain.
std::vector<FitLaw> FitLaws(const std::vector<MaterialFit>& fits);

// One fold of a joint fit's cross-validation: the setting fitted on the
// training shots without `scene` (leave_out) or on `scene` alone, measured on
// `scene`'s held-out shots (its training cameras when left out, the
// validation cameras when fitted alone), beside the defaults there.
struct CrossFold {
  std::string scene;
  bool leave_out = true;
  std::vector<double> values;
  ObjectiveValue held_out, held_out_defaults;
};

// A joint fit (FitConfig::IsJoint) of one variant on one material.
struct JointFit {
  std::string variant, material, ndf;
  double alpha = 0;
  std::vector<std::string> params;
  std::vector<FitAxis> bounds;
  FitND search;
  double seconds = 0;
  ObjectiveValue train, validate;  // at the fitted setting
  std::vector<double> defaults;    // the variant's own setting, compared with
  ObjectiveValue train_defaults, validate_defaults;
  std::vector<CrossFold> folds;
  nlohmann::json ToJson() const;
  static JointFit FromJson(const nlohmann::json& j);  // throws nlohmann::json::exception
};

struct FitOutcome {
  std::vector<MaterialFit> fits;
  std::vector<JointFit> joint_fits;
  std::vector<FitLaw> laws;
  std::optional<Error> error;  // set when a fit stopped; the fits before it are complete
};

// Runs every fit of the spec. Evaluations are jobs: cached in the store at
// options.db_path by job id (a rerun re-renders nothing) and their
// references in options.work_dir; fitted rows go to the store's `fits` table.
// `result` gets a line per fitted material; `progress` one per job rendered.
FitOutcome RunFits(const Spec& spec, const RunOptions& options,
                   const std::function<void(const std::string&)>& result = {},
                   const std::function<void(const std::string&)>& progress = {});

}  // namespace shimmer::experiments
