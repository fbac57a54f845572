// Finding variants in the catalogue (Variants(), generated from
// shading/variant_table.json), combinations GEOMETRIC+NORMALMAP, and the
// names of NDFs and lights.
#include <cmath>
#include <deque>
#include <mutex>
#include <optional>
#include <string>

#include "shimmer/shading/shading.h"

namespace shimmer::shading {

namespace {

// Combinations GEOMETRIC+NORMALMAP, made when first asked for.
const VariantInfo* FindCombination(std::string_view name) {
  const std::size_t plus = name.find('+');
  if (plus == std::string_view::npos) return nullptr;
  static std::mutex mutex;
  static std::deque<std::pair<std::string, VariantInfo>> made;  // names and summaries own their text
  static std::deque<std::string> texts;
  std::lock_guard<std::mutex> lock(mutex);
  for (const auto& [n, info] : made)
    if (n == name) return &info;
  const VariantInfo* geo = nullptr;
  const VariantInfo* nm = nullptr;
  for (const VariantInfo& v : Variants()) {
    if (v.name == name.substr(0, plus)) geo = &v;
    if (v.name == name.substr(plus + 1)) nm = &v;
  }
  if (!geo || !nm || FiltersNormalMap(*geo) || !FiltersNormalMap(*nm) || NeedsSgLight(*geo) || geo->glints)
    return nullptr;
  auto& [own_name, info] = made.emplace_back(std::string(name), *geo);
  info.name = own_name;
  info.id = geo->id + nm->id;
  info.summary = texts.emplace_back(std::string(nm->name) + " on the normal map, then " + std::string(geo->name) +
                                    " on the roughness it gives: " + std::string(geo->summary));
  info.source = texts.emplace_back(std::string(geo->source) + "; " + std::string(nm->source));
  info.widens_roughness = geo->widens_roughness || nm->widens_roughness;
  info.reads_footprint = geo->reads_footprint || nm->reads_footprint;
  info.params.insert(info.params.end(), nm->params.begin(), nm->params.end());
  return &info;
}

}  // namespace

const VariantInfo* FindVariant(std::string_view name) {
  for (const VariantInfo& v : Variants())
    if (v.name == name) return &v;
  return FindCombination(name);
}

std::optional<Ndf> ParseNdf(std::string_view name) {
  if (name == "ggx") return Ndf::kGgx;
  if (name == "beckmann") return Ndf::kBeckmann;
  if (name == "blinn-phong") return Ndf::kBlinnPhong;
  if (name == "glints") return Ndf::kGlints;
  return std::nullopt;
}

std::string_view NdfName(Ndf ndf) {
  if (ndf == Ndf::kBlinnPhong) return "blinn-phong";
  if (ndf == Ndf::kGlints) return "glints";
  return ndf == Ndf::kGgx ? "ggx" : "beckmann";
}

std::string_view LightTypeName(LightType type) {
  if (type == LightType::kSphere) return "sphere";
  if (type == LightType::kSg) return "sg";
  return "directional";
}

std::optional<std::string> MaterialMismatch(const VariantInfo& info, Ndf ndf) {
  const bool glint_material = ndf == Ndf::kGlints;
  if (info.glints && !glint_material)
    return "variant " + std::string(info.name) +
           " shades glint materials only; use a glint material such as glints:0.3,local=0.03,density=1e4";
  if (glint_material && !info.glints && info.id != 0)
    return "a glint material takes none, supersample-N, glints-zk16, glints-zk16-counting, glints-db23, glints-points, "
           "glints-naive or glints-smooth, not " +
           std::string(info.name);
  if (info.ggx_only && ndf != Ndf::kGgx) return "variant " + std::string(info.name) + " filters GGX only; use a ggx material";
  return std::nullopt;
}

}  // namespace shimmer::shading
