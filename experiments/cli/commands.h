// Each subcommand lives in its own file and registers itself on the app.
#pragma once

#include <CLI/CLI.hpp>

#include <stdexcept>
#include <string>
#include <utility>

#include "runner.h"

namespace shimmer::cli {

// Thrown by a subcommand for bad input; main prints "shimmer: error: <what>"
// and exits with 2. Anything else that escapes exits with 1.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// "--param name=value" as a (name, value) pair; UsageError for anything else.
std::pair<std::string, double> ParseParamOption(const std::string& text);

// Fills db_path and work_dir: the given paths, else runs/<spec>/<db_file> and
// runs/<spec>/frames; creates their directories (UsageError when it cannot).
void StorePaths(const std::string& spec_name, const std::string& db, const std::string& work,
                const std::string& db_file, experiments::RunOptions* ro);

void AddVariantsCommand(CLI::App& app);
void AddNdfCommand(CLI::App& app);
void AddRenderCommand(CLI::App& app);
void AddMetricsCommand(CLI::App& app);
void AddRunCommand(CLI::App& app);
void AddMergeCommand(CLI::App& app);
void AddSweepCommand(CLI::App& app);
void AddReportCommand(CLI::App& app);
void AddFitCommand(CLI::App& app);

}  // namespace shimmer::cli
