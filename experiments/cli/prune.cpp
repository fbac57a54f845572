// `shimmer prune DB [--dry-run]`: removes the rows older code or content left
// in a results store (a changed kernel moves the ids of its jobs, and the old
// rows would otherwise stay in the file for good).
#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "shimmer/experiments/job.h"
#include "shimmer/experiments/result_store.h"
#include "shimmer/experiments/runner.h"

namespace shimmer::cli {

void AddPruneCommand(CLI::App& app) {
  auto db = std::make_shared<std::string>();
  auto dry_run = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "prune", "Remove a results store's rows that this shimmer would not make as they are (older kernels, metrics or "
      "content, external sequences included)");
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
      auto rows = (*store)->All();
      if (!rows) return rows.failure();
      const experiments::CurrentRowSet current = experiments::FindCurrentRows(*rows);
      return (*store)->PruneStale(current.jobs, current.costs, *dry_run);
    }();
    lock->Discard();
    const auto p = Take(std::move(pruned));
    std::printf("%s: %s %zu jobs of older code or content, %zu convergence checks and %zu benchmark costs; "
                "%zu jobs kept (%zu external)\n",
                db->c_str(), *dry_run ? "would remove" : "removed", p.jobs, p.shots, p.benchmarks,
                p.kept_jobs, p.kept_external);
  });
}

}  // namespace shimmer::cli
