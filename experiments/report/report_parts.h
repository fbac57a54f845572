// The pieces of a report, each written by its own file: the CSV of every row
// (report_csv.cpp), the markdown tables and summary (report_markdown.cpp),
// and the plot data and gnuplot scripts (report_plots.cpp).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "shimmer/experiments/result_store.h"

namespace shimmer::experiments::report {

// One table and set of plots: the rows of a (scene, material, camera,
// derivatives) shot, sorted by label. `none` and `supersample-N` read no
// derivatives; they join every derivative group of their shot as baselines.
struct Group {
  std::string key;  // "scene / material / camera / derivatives"
  std::vector<const JobResult*> rows;
};
std::vector<Group> GroupRows(const std::vector<JobResult>& rows);

// Speed against error for a group's rows, in its order, and which rows are
// on the Pareto front of (ms per frame, tv_err) and of (ms per frame, relmse).
struct Costs {
  std::vector<double> ms, tv_err, relmse;
  std::vector<bool> front_tv_err, front_relmse;
};
Costs CostsOf(const Group& group);

// "variant name=value ...".
std::string Label(const JobResult& row);
// The metrics' region, e.g. "highlight" or "frame (highlight mask empty)".
std::string Region(const JobResult& row);
bool IsSupersample(const JobResult& row);

std::string Csv(const std::vector<JobResult>& rows);
std::string Markdown(const std::vector<Group>& groups, const std::string& title, std::size_t jobs);

struct PlotFile {
  std::string name, text;
  bool script = false;  // a gnuplot script to run
};
std::vector<PlotFile> Plots(const Group& group);

}  // namespace shimmer::experiments::report
