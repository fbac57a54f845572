// The variant parameters (ParamFields(), generated from
// shading/variant_table.json): lookup, validation, and the resolution of
// defaults and overrides.
#include <cmath>
#include <cstdio>
#include <string>

#include "shimmer/core/number_text.h"
#include "shimmer/shading/shading.h"

namespace shimmer::shading {

const ParamField* FindParamField(std::string_view name) {
  for (const ParamField& f : ParamFields())
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
    for (const ParamField& p : ParamFields()) list += (list.empty() ? "" : ", ") + std::string(p.name);
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
