// `shimmer report DB -o DIR`: report.md, report.html, report.csv and plots from a results store.
#include <cstdio>

#include "commands.h"
#include "shimmer/experiments/report.h"
#include "shimmer/experiments/result_store.h"

namespace shimmer::cli {

void AddReportCommand(CLI::App& app) {
  auto db = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto title = std::make_shared<std::string>("shimmer report");
  CLI::App* cmd =
      app.add_subcommand("report", "Write report.md, report.html, report.csv and plots from a results store");
  cmd->add_option("db", *db, "Results store (from shimmer run); only read")->required();
  cmd->add_option("-o,--output", *out, "Report directory, e.g. results/quick")->required();
  cmd->add_option("--title", *title, "Heading of report.md")->capture_default_str();
  cmd->callback([db, out, title] {
    RequireCreatableDirectory("--output", *out);
    auto store = Take(experiments::ResultStore::Open(*db, experiments::ResultStore::Mode::kReadOnly));
    const auto rows = Take(store->All());
    if (rows.empty()) throw UsageError(*db + ": the results store has no finished jobs");
    std::vector<std::string> warnings;
    Check(experiments::WriteReport(rows, *title, *out, &warnings));
    for (const std::string& w : warnings) std::fprintf(stderr, "shimmer: warning: %s\n", w.c_str());
    std::printf("report: %s/report.md and %s/report.html\n", out->c_str(), out->c_str());
  });
}

}  // namespace shimmer::cli
