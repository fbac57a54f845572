#include "shimmer/experiments/report.h"

#include <algorithm>
#include <map>
#include <set>
#include <sstream>

#include "report_parts.h"
#include "shimmer/core/gnuplot.h"
#include "shimmer/experiments/output_files.h"
#include "shimmer/renderer/shading.h"

namespace shimmer::experiments {

namespace report {

std::string Label(const JobResult& r) {
  std::string label = r.job.variant;
  for (const auto& [k, v] : r.job.params) {
    std::ostringstream s;
    s << " " << k << "=" << v;
    label += s.str();
  }
  return label;
}

std::string Region(const JobResult& r) { return r.metrics.value("region", std::string("frame")); }

bool IsSupersample(const JobResult& r) {
  auto name = shading::ParseVariantName(r.job.variant);
  return name && name->kind == shading::VariantName::Kind::kSupersample;
}

std::vector<Group> GroupRows(const std::vector<JobResult>& rows) {
  std::map<std::string, std::vector<const JobResult*>> groups;
  std::map<std::string, std::set<std::string>> sources_of_shot;
  auto shot = [](const JobResult& r) { return r.job.scene + " / " + r.job.material + " / " + r.job.camera; };
  for (const JobResult& r : rows) sources_of_shot[shot(r)].insert(r.job.derivatives);
  for (const JobResult& r : rows) {
    if (ReadsDerivatives(r.job.variant)) {
      groups[shot(r) + " / " + r.job.derivatives].push_back(&r);
      continue;
    }
    for (const std::string& source : sources_of_shot[shot(r)]) groups[shot(r) + " / " + source].push_back(&r);
  }
  std::vector<Group> out;
  for (auto& [key, group] : groups) {
    std::sort(group.begin(), group.end(), [](const JobResult* a, const JobResult* b) { return Label(*a) < Label(*b); });
    out.push_back({key, std::move(group)});
  }
  return out;
}

Costs CostsOf(const Group& group) {
  Costs c;
  for (const JobResult* r : group.rows) {
    c.ms.push_back(r->gpu_ms_per_frame);
    c.tv_err.push_back(Metric(r->metrics, "tv_err"));
    c.relmse.push_back(Metric(r->metrics, "relmse"));
  }
  c.front_tv_err.assign(group.rows.size(), false);
  c.front_relmse.assign(group.rows.size(), false);
  for (int i : ParetoFront(c.ms, c.tv_err)) c.front_tv_err[i] = true;
  for (int i : ParetoFront(c.ms, c.relmse)) c.front_relmse[i] = true;
  return c;
}

}  // namespace report

std::vector<int> ParetoFront(const std::vector<double>& cost, const std::vector<double>& error) {
  std::vector<int> front;
  for (std::size_t i = 0; i < cost.size(); ++i) {
    bool dominated = false;
    for (std::size_t j = 0; j < cost.size() && !dominated; ++j)
      dominated = j != i && cost[j] <= cost[i] && error[j] <= error[i] && (cost[j] < cost[i] || error[j] < error[i]);
    if (!dominated) front.push_back(int(i));
  }
  return front;
}

Status WriteReport(const std::vector<JobResult>& rows, const std::string& title, const std::string& out_dir,
                   std::vector<std::string>* warnings) {
  if (rows.empty()) return Status::Failure("the results store has no finished jobs");
  auto staged = StagedDirectory::Create(out_dir);
  if (!staged) return staged.failure();
  StagedDirectory& dir = **staged;
  if (Status s = dir.Write("report.csv", report::Csv(rows)); !s) return s;
  const std::vector<report::Group> groups = report::GroupRows(rows);
  std::vector<std::string> scripts;
  for (const report::Group& group : groups)
    for (const report::PlotFile& f : report::Plots(group)) {
      if (Status s = dir.Write(f.name, f.text); !s) return s;
      if (f.script) scripts.push_back(f.name);
    }
  for (const std::string& script : scripts)
    if (Status s = RunGnuplot(dir.staging(), script); !s) {
      // gnuplot missing or failing costs the plots; a plot cut short (a full disk) fails the report.
      if (s.code() == ErrorCode::kIo) return dir.Unstaged(s.failure());
      if (warnings) warnings->push_back(s.error());
    }
  if (Status s = dir.Write("report.md", report::Markdown(groups, title, rows.size())); !s) return s;
  return dir.Commit("report.md");
}

}  // namespace shimmer::experiments
