// `shimmer merge A.db B.db ... -o all.db`: joins result stores (e.g. shards).
#include <cstdio>

#include "commands.h"
#include "shimmer/experiments/result_store.h"

namespace shimmer::cli {

void AddMergeCommand(CLI::App& app) {
  auto inputs = std::make_shared<std::vector<std::string>>();
  auto output = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("merge", "Join result stores (shards) into one");
  cmd->add_option("stores", *inputs, "Result stores to join")->required();
  cmd->add_option("-o,--output", *output, "The joined store (created or extended)")->required();
  cmd->callback([inputs, output] {
    RequireParentDirectory("--output", *output);
    const std::size_t jobs = Take(experiments::MergeStores(*inputs, *output));
    std::printf("%s: %zu jobs\n", output->c_str(), jobs);
  });
}

}  // namespace shimmer::cli
