// `shimmer merge A.db B.db ... -o all.db`: joins result stores (e.g. shards).
#include <cstdio>

#include "commands.h"
#include "result_store.h"

namespace shimmer::cli {

void AddMergeCommand(CLI::App& app) {
  auto inputs = std::make_shared<std::vector<std::string>>();
  auto output = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("merge", "Join result stores (shards) into one");
  cmd->add_option("stores", *inputs, "Result stores to join")->required();
  cmd->add_option("-o,--output", *output, "The joined store (created or extended)")->required();
  cmd->callback([inputs, output] {
    auto [store, error] = experiments::ResultStore::Open(*output);
    if (!store) throw UsageError(error);
    for (const std::string& in : *inputs)
      if (std::string e = store->MergeFrom(in); !e.empty()) throw UsageError(e);
    std::printf("%s: %zu jobs\n", output->c_str(), store->All().size());
  });
}

}  // namespace shimmer::cli
