// shimmer: measures the temporal stability of specular highlights.
#include <cstdio>
#include <exception>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"shimmer: temporal stability of specular highlights under camera motion"};
  app.require_subcommand(1);
  app.fallthrough(false);
  shimmer::cli::AddVariantsCommand(app);
  shimmer::cli::AddNdfCommand(app);
  shimmer::cli::AddRenderCommand(app);
  shimmer::cli::AddMetricsCommand(app);
  shimmer::cli::AddRunCommand(app);
  shimmer::cli::AddMergeCommand(app);
  shimmer::cli::AddSweepCommand(app);
  shimmer::cli::AddReportCommand(app);
  shimmer::cli::AddFitCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const shimmer::cli::UsageError& e) {
    std::fprintf(stderr, "shimmer: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shimmer: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
