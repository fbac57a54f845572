// The --out directory: everything a person needs to look at one run.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/metrics/metrics_report.h"

namespace shimmer::metrics {

// Writes into `dir` (created if needed), all files or none: they are staged
// in a hidden directory inside it and renamed together, metrics.json last.
//   metrics.json                       the --json object
//   tv_test.exr/.png  tv_ref.*  tv_err.*  energy_bias.*   per-pixel maps
//                                      (EXR: one float channel Y; PNG: heatmap + legend)
//   spectrum.csv, spectrum.gp          the flicker PSD and the gnuplot script that plots it
//   spectrum.png                       when gnuplot is installed (else a warning)
// Non-fatal problems (no gnuplot) are appended to `warnings`.
Status WriteReportFiles(const MetricsReport& report, const std::filesystem::path& dir,
                        std::vector<std::string>* warnings);

}  // namespace shimmer::metrics
