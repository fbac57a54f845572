// Plots are drawn by gnuplot from scripts kept beside their data, so that a
// user can restyle a plot and rerun `gnuplot name.gp` by hand.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "shimmer/core/result.h"

namespace shimmer {

bool GnuplotAvailable();

// Runs `gnuplot script` with `dir` as the working directory. The error (a
// warning to most callers: the data and script are still there) names the
// script and says whether gnuplot is missing or failed; with code kIo, an
// error to every caller, it names a plot that was cut short (a full disk).
Status RunGnuplot(const std::filesystem::path& dir, const std::string& script);

// Writes `dir/<script_name>` and draws `output` (the script's `set output`)
// from it. Meant for a StagedDirectory's staging directory, which makes the
// plot appear together with its data or not at all. Returns a warning when
// the plot could not be drawn (no gnuplot, a script gnuplot rejects; no plot
// is left); an error when the script or the plot could not be written (then
// neither is left).
Result<std::optional<std::string>> WritePlot(const std::filesystem::path& dir, const std::string& script_name,
                                             const std::string& output, const std::string& script_text);

}  // namespace shimmer
