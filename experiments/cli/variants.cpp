// `shimmer variants`: the filter catalogue with parameters, defaults and sources.
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "shimmer/renderer/shading.h"

namespace shimmer::cli {

namespace {

nlohmann::json CatalogueJson() {
  nlohmann::json list = nlohmann::json::array();
  for (const shading::VariantInfo& v : shading::Variants()) {
    nlohmann::json params = nlohmann::json::array();
    for (const shading::ParamInfo& p : v.params)
      params.push_back({{"name", p.name}, {"default", p.default_value}, {"meaning", p.meaning}});
    list.push_back({{"name", v.name},
                    {"summary", v.summary},
                    {"source", v.source},
                    {"params", params},
                    {"widens_roughness", v.widens_roughness},
                    {"ndf", v.ggx_only ? "ggx" : "any"}});
  }
  return list;
}

void PrintCatalogue() {
  for (const shading::VariantInfo& v : shading::Variants()) {
    std::printf("%s%s\n", std::string(v.name).c_str(), v.ggx_only ? "  [GGX materials only]" : "");
    std::printf("    %s\n", std::string(v.summary).c_str());
    for (const shading::ParamInfo& p : v.params)
      std::printf("    --param %s=%g  %s\n", std::string(p.name).c_str(), p.default_value,
                  std::string(p.meaning).c_str());
    std::printf("    source: %s\n\n", std::string(v.source).c_str());
  }
}

}  // namespace

void AddVariantsCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("variants", "List the filter variants, their parameters and sources");
  auto json = std::make_shared<bool>(false);
  cmd->add_flag("--json", *json, "Print the catalogue as a JSON array");
  cmd->callback([json] {
    if (*json)
      std::cout << CatalogueJson().dump(2) << "\n";
    else
      PrintCatalogue();
  });
}

}  // namespace shimmer::cli
