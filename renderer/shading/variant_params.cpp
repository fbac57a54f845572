// The variant parameters (fp_max, fp_min_cap, sigma2, kappa, nm_scale and the
// three curvature constants): their one
// table, validation, and the resolution of defaults and overrides.
#include <cmath>
#include <cstdio>
#include <string>

#include "shimmer/core/number_text.h"
#include "shimmer/renderer/shading.h"

namespace shimmer::shading {

namespace {

// Upper bounds sit where a parameter stops changing anything, or, for the
// kernel constants, far beyond what engines use (<= 1) yet low enough that the
// renderer's float push constants and their products stay finite. NaN,
// infinities and negative widths are never a parameter.
constexpr ParamField kParamFields[] = {
    {"fp_max", &Params<double>::fp_max, 0, 1e4,
     "upper clamp on the footprint half-sides; half-sides are capped at 1e4 (FOOTPRINT_MAX in variants.glsl)"},
    {"fp_min_cap", &Params<double>::fp_min_cap, 0, 100,
     "fp_min = min(alpha, fp_min_cap); alpha is clamped to 100 (ALPHA_MAX in common.glsl)"},
    {"sigma2", &Params<double>::sigma2, 0, 1e4, "screen-space variance of the filtering kernel"},
    {"kappa", &Params<double>::kappa, 0, 1e4, "clamp on the kernel roughness"},
    {"nm_scale", &Params<double>::nm_scale, 0, 100,
     "scale on the roughness variance a normal-map filter adds (widened alpha^2 is capped at 1)"},
    // pow(curvature, E) with E > 0 keeps a flat surface's 0 at 0; the result
    // is saturated, so scales and biases beyond these change nothing.
    {"curvature_scale", &Params<double>::curvature_scale, 0, 1e4, "scale S on pow(curvature, E)"},
    {"curvature_bias", &Params<double>::curvature_bias, -1, 1, "bias B added to S pow(curvature, E)"},
    {"curvature_exponent", &Params<double>::curvature_exponent, 0.0625, 10,
     "exponent E on the curvature max(|dn/dx|^2, |dn/dy|^2)"},
};

}  // namespace

std::span<const ParamField> ParamFields() { return kParamFields; }

const ParamField* FindParamField(std::string_view name) {
  for (const ParamField& f : kParamFields)
    if (f.name == name) return &f;
  return nullptr;
}

double ParamValue(const Params<double>& params, std::string_view name) {
  const ParamField* f = FindParamField(name);
  return f ? params.*(f->member) : std::nan("");
}

Status ValidateParam(std::string_view name, double value) {
  const ParamField* f = FindParamField(name);
  if (!f) {
    std::string list;
    for (const ParamField& p : kParamFields) list += (list.empty() ? "" : ", ") + std::string(p.name);
    return Status::Failure("unknown parameter '" + std::string(name) + "' (the parameters are " + list + ")");
  }
  if (!std::isfinite(value) || value < f->lo || value > f->hi)
    return Status::Failure("parameter " + std::string(name) + " must be >= " + NumberText(f->lo) +
                           " and <= " + NumberText(f->hi) + ", got " + NumberText(value));
  return Ok();
}

Result<Params<double>> ResolveParams(const VariantInfo& info,
                                     std::span<const std::pair<std::string, double>> overrides) {
  Params<double> values;
  for (const ParamInfo& p : info.params) values.*(FindParamField(p.name)->member) = p.default_value;
  for (const auto& [name, value] : overrides) {
    bool known = false;
    for (const ParamInfo& p : info.params) known = known || p.name == name;
    if (!known) {
      std::string list;
      for (const ParamInfo& p : info.params) list += (list.empty() ? "" : ", ") + std::string(p.name);
      return Result<Params<double>>::Failure("variant " + std::string(info.name) + " has no parameter '" + name + "'" +
                                             (list.empty() ? " (it takes none)" : " (it takes: " + list + ")"));
    }
    if (Status s = ValidateParam(name, value); !s) return s.failure();
    values.*(FindParamField(name)->member) = value;
  }
  return values;
}

}  // namespace shimmer::shading
