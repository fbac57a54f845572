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

}  // namespace shimmer::experiments
