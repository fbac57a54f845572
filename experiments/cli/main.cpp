// shimmer: measures the temporal stability of specular highlights.
#include <csignal>
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "commands.h"

int main(int argc, char** argv) {
  // Past a file-size limit (ulimit -f), writes then fail with EFBIG and get
  // the usual message and clean-up, instead of the signal killing the process
  // with a half-written file.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"shimmer: temporal stability of specular highlights under camera motion"};
  app.require_subcommand(1);
  app.fallthrough(false);
  shimmer::cli::AddVariantsCommand(app);
  shimmer::cli::AddNdfCommand(app);
  shimmer::cli::AddRenderCommand(app);
  shimmer::cli::AddMetricsCommand(app);
  shimmer::cli::AddVideoCommand(app);
  shimmer::cli::AddRunCommand(app);
  shimmer::cli::AddMergeCommand(app);
  shimmer::cli::AddPruneCommand(app);
  shimmer::cli::AddSweepCommand(app);
  shimmer::cli::AddReportCommand(app);
  shimmer::cli::AddFitCommand(app);
  shimmer::cli::AddExportBlenderCommand(app);
  shimmer::cli::AddSgAccuracyCommand(app);
  shimmer::cli::AddSceneCommand(app);
  using shimmer::cli::kExitBadInput;
  using shimmer::cli::kExitFailure;
  try {
    // CLI11 would call "shimmer rendr" a missing subcommand; the user typed one.
    if (argc > 1 && argv[1][0] != '-') {
      std::string names;
      bool known = false;
      for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
        known = known || sub->get_name() == argv[1];
        names += (names.empty() ? "" : ", ") + sub->get_name();
      }
      if (!known)
        throw shimmer::cli::UsageError("unknown subcommand '" + std::string(argv[1]) + "' (one of " + names +
                                       "; see shimmer --help)");
    }
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11's own exit codes (104-109) would tell scripts nothing; every
    // problem with the command line is bad input.
    std::fprintf(stderr, "shimmer: error: %s (see shimmer --help)\n", e.what());
    return kExitBadInput;
  } catch (const shimmer::cli::UsageError& e) {
    std::fprintf(stderr, "shimmer: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const shimmer::cli::CommandError& e) {
    std::fprintf(stderr, "shimmer: error: %s\n", e.what());
    return e.code == shimmer::ErrorCode::kBadInput ? kExitBadInput : kExitFailure;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "shimmer: error: out of memory\n");
    return kExitFailure;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "shimmer: error: %s\n", e.what());
    return kExitFailure;
  }
  return 0;
}
