// `shimmer variants`: the filter catalogue with parameters, defaults and
// sources; with --file, a user's variant files, checked and described.
#include <cstdio>
#include <iostream>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/shading/shading.h"
#include "shimmer/shading/user_variant.h"

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
                    {"ndf", v.glints ? "glints" : v.ggx_only ? "ggx" : "any"}});
  }
  return list;
}

void PrintCatalogue() {
  for (const shading::VariantInfo& v : shading::Variants()) {
    std::printf("%s%s\n", std::string(v.name).c_str(),
                v.glints ? "  [glint materials only]" : v.ggx_only ? "  [GGX materials only]" : "");
    std::printf("    %s\n", std::string(v.summary).c_str());
    for (const shading::ParamInfo& p : v.params)
      std::printf("    --param %s=%g  %s\n", std::string(p.name).c_str(), p.default_value,
                  std::string(p.meaning).c_str());
    std::printf("    source: %s\n\n", std::string(v.source).c_str());
  }
}

nlohmann::json UserVariantJson(const shading::UserVariant& v) {
  nlohmann::json params = nlohmann::json::array();
  for (const shading::UserParam& p : v.params)
    params.push_back({{"name", p.name}, {"default", p.default_value}, {"range", {p.lo, p.hi}}, {"meaning", p.meaning}});
  return {{"file", v.file}, {"summary", v.summary}, {"params", params}, {"declared", v.declared}};
}

// Each file parsed and compiled into the render kernel (no device needed), so
// that a file listed here is one a render, spec, sweep or fit accepts.
void DescribeFiles(const std::vector<std::string>& files, bool json) {
  nlohmann::json list = nlohmann::json::array();
  for (const std::string& path : files) {
    const shading::UserVariant v = Take(shading::LoadUserVariant(path));
    if (Status s = render::CheckUserVariant(v); !s) throw CommandError(s.failure());
    if (json)
      list.push_back(UserVariantJson(v));
    else
      std::printf("%s\n", shading::DescribeUserVariant(v).c_str());
  }
  if (json) std::cout << list.dump(2) << "\n";
}

}  // namespace

void AddVariantsCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("variants", "List the filter variants, their parameters and sources");
  auto json = std::make_shared<bool>(false);
  auto files = std::make_shared<std::vector<std::string>>();
  cmd->add_flag("--json", *json, "Print the catalogue as a JSON array");
  cmd->add_option("--file", *files,
                  "Check and describe a user variant file instead: its summary and declared parameters (repeatable)");
  cmd->callback([json, files] {
    if (!files->empty())
      DescribeFiles(*files, *json);
    else if (*json)
      std::cout << CatalogueJson().dump(2) << "\n";
    else
      PrintCatalogue();
  });
}

}  // namespace shimmer::cli
