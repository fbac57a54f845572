// The fit's part of a report: fit.md (per material the fitted value, its
// training objective, the objective at the published defaults, the same on
// held-out shots; the closed form across materials), fit.json, and one J(p)
// plot per variant with every material's curve and optimum.
#pragma once

#include <string>
#include <vector>

#include "shimmer/experiments/fit_run.h"
#include "shimmer/experiments/spec.h"

namespace shimmer::experiments {

Status WriteFitReport(const FitOutcome& outcome, const Spec& spec, const std::string& out_dir,
                      std::vector<std::string>* warnings);

// The fits of a fit.json that WriteFitReport wrote, as RunFits returned
// them (the closed forms recomputed from the fits by FitLaws), so that a
// report can be written again without rendering (`shimmer fit --from-json`).
// One error naming the file when it cannot be read or is not a fit.json.
Result<FitOutcome> ReadFitOutcome(const std::string& path);

// Its joint fits; an error too when it has none.
Result<std::vector<JointFit>> ReadJointFits(const std::string& path);

// One row of the engine-settings table (fit.md, and the report's overview):
// a joint fit's setting under the engine's own knob names beside the
// setting the engine ships, their J, and whether held-out shots separate them.
struct EngineSettingRow {
  std::string material, engine, fitted, shipped, train, validate, held_out;
};
std::vector<EngineSettingRow> EngineSettingRows(const std::vector<JointFit>& fits);

// Cross-validation folds of the joint fits against the shipped setting:
// how many held-out verdicts fall each way.
struct TransferCount {
  int fitted_better = 0, shipped_better = 0, within = 0;
};
TransferCount CountTransfer(const std::vector<JointFit>& fits, bool leave_out);

}  // namespace shimmer::experiments
