// The report from a results store, written into one directory: report.md
// (an overview across shots: leaderboard, heatmap, recommendation per
// roughness and geometry class; then the per-shot tables), report.html (the
// same on one self-contained page), report.csv, and gnuplot scripts with
// their SVGs (heatmap, speed against error with the Pareto front, flicker
// spectra).
#pragma once

#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "shimmer/core/result.h"

#include "shimmer/experiments/fit_run.h"
#include "shimmer/experiments/result_store.h"

namespace shimmer::experiments {

// Indices of the rows on the Pareto front of (cost, error): no other row is
// at most as costly and at most as wrong with one of them strictly better.
// A NaN cost (an untimed row) is neither on the front nor dominates.
std::vector<int> ParetoFront(const std::vector<double>& cost, const std::vector<double>& error);

// A store keeps the rows of every version of the code it was run with (a
// changed kernel moves the ids of its jobs), and a report of old and new
// rows side by side would show a variant twice. When some rows' ids are in
// `current` (FindCurrentRows) and others not, only the current ones (and
// those of external sequences, which no kernel renders) are kept and `note`
// says how many were left out; when none is current, the rows are returned
// as they are and `note` says so.
std::vector<JobResult> CurrentRows(std::vector<JobResult> rows, const std::set<std::string>& current,
                                   std::string* note);

// Writes the report for `rows` into `out_dir` (created): every file or none
// (StagedDirectory), report.md last. Plots need gnuplot; without it the
// scripts and data are still written and a warning names the scripts.
//
// `video`, when given, writes one grid MP4 per shot table from the table's
// rows (in its order: `none` first) to the file it is handed; the table
// links it (kVideoSuffix after the table's plot stem).
using ShotVideoWriter = std::function<Status(const std::vector<const JobResult*>& rows, const std::filesystem::path& file)>;
inline constexpr const char* kVideoSuffix = "_grid.mp4";
//
// `engine_fits`, when given (ReadJointFits of a fit.json), are shown in the
// overview's "Beyond the papers" part beside the store's own results.
Status WriteReport(const std::vector<JobResult>& rows, const std::string& title, const std::string& out_dir,
                   std::vector<std::string>* warnings, const ShotVideoWriter& video = {},
                   const std::vector<JointFit>& engine_fits = {});

}  // namespace shimmer::experiments
