#include "variant_resolution.h"

#include <cmath>
#include <filesystem>

namespace shimmer::render {

Result<ResolvedVariant> ResolveVariant(const RenderSettings& s) {
  using R = Result<ResolvedVariant>;
  ResolvedVariant v;
  const bool reference = s.reference_spp > 0 || s.reference_tolerance > 0;
  if (!s.variant_file.empty()) {
    if (reference) return R::Failure("a reference renders variant none, not a variant file");
    if (s.material.ndf == shading::Ndf::kGlints)
      return R::Failure("a variant file filters a smooth NDF; a glint material takes none and the glint variants");
    auto user = shading::LoadUserVariant(s.variant_file);
    if (!user) return user.failure();
    v.name = "user:" + std::filesystem::path(s.variant_file).filename().string();
    v.id = 0;
    // The parameters the file declares (or the four built-in ones), each
    // checked against its declared range.
    auto params = shading::ResolveUserParams(*user, s.param_overrides);
    if (!params) return params.failure();
    v.user = std::make_shared<const shading::UserVariant>(std::move(*user));
    v.params = params->values;
    v.shown_params = params->shown;
    return v;
  }
  auto name = shading::ParseVariantName(s.variant);
  if (!name) return name.failure();
  if (name->kind == shading::VariantName::Kind::kSupersample) {
    if (reference) return R::Failure("a reference is already supersampled; use variant none with reference_spp");
    if (!s.param_overrides.empty()) return R::Failure("variant '" + s.variant + "' takes no parameters");
  }
  const shading::VariantInfo& info = *name->info;
  if (reference && info.id != 0) return R::Failure("a reference renders variant none, not " + s.variant);
  if (shading::NeedsSgLight(info) && s.scene.light.type != shading::LightType::kSg)
    return R::Failure("variant " + s.variant + " shades spherical-Gaussian lights only, and scene '" + s.scene.name +
                      "' has a " + std::string(shading::LightTypeName(s.scene.light.type)) +
                      " light (use an SG-lit scene such as sg-sphere-field)");
  if (shading::FiltersNormalMap(info) && !(scene::SceneFeatures(s.scene) & shading::kSceneNormalMaps))
    return R::Failure("variant " + s.variant + " filters normal maps, and scene '" + s.scene.name +
                      "' has none (use a scene with a normal map, such as nm-plane)");
  if (auto mismatch = shading::MaterialMismatch(info, s.material.ndf)) return R::Failure(*mismatch);
  auto params = shading::ResolveParams(info, s.param_overrides);
  if (!params) return params.failure();
  v.name = s.variant;
  v.id = info.id;
  v.params = *params;
  for (const shading::ParamInfo& p : info.params)
    v.shown_params.push_back({std::string(p.name), shading::ParamValue(*params, p.name)});
  v.reference = reference;
  v.spp_n = reference ? (s.reference_spp > 0 ? s.reference_spp : 4) : name->spp_n;
  return v;
}

}  // namespace shimmer::render
