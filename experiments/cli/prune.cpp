// `shimmer prune DB [--dry-run]`: removes the rows older shading cores left
// in a results store (a changed core moves every job id, and the old rows
// would otherwise stay in the file for good).
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/result_store.h"

namespace shimmer::cli {

void AddPruneCommand(CLI::App& app) {
  auto db = std::make_shared<std::string>();
  auto dry_run = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "prune", "Remove a results store's rows of older shading cores (external sequences are kept)");
  cmd->add_option("db", *db, "Results store (from shimmer run)")->required();
  cmd->add_flag("--dry-run", *dry_run, "Count what would be removed; change nothing");
  cmd->callback([db, dry_run] {
    // Opening a missing store for writing would create an empty one.
    if (!std::filesystem::is_regular_file(*db)) throw UsageError(*db + ": no such results store");
    // A run writing the store at the same time would race the deletions. The
    // lock file goes again with the command when it made one.
    auto lock = Take(experiments::StoreLock::Acquire(*db));
    auto pruned = [&]() -> Result<experiments::ResultStore::Pruned> {
      using Mode = experiments::ResultStore::Mode;
      auto store = experiments::ResultStore::Open(*db, *dry_run ? Mode::kReadOnly : Mode::kReadWrite);
      if (!store) return store.failure();
      return (*store)->PruneOtherCores(experiments::ShadingCoreVersion(), *dry_run);
    }();
    lock->Discard();
    const auto p = Take(std::move(pruned));
    std::printf("%s: %s %zu jobs of %zu older shading cores, %zu convergence checks and %zu benchmark costs; "
                "%zu jobs kept (%zu external)\n",
                db->c_str(), *dry_run ? "would remove" : "removed", p.jobs, p.cores, p.shots, p.benchmarks,
                p.kept_jobs, p.kept_external);
  });
}

}  // namespace shimmer::cli
