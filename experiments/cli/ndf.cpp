// `shimmer ndf`: evaluates one variant's filtered NDF at one slope, on the CPU,
// in float or double, through the same GLSL the renderer runs.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "shimmer/core/number_text.h"
#include "shimmer/renderer/shading.h"

namespace shimmer::cli {

namespace {

struct NdfOptions {
  std::string variant = "none";
  std::string ndf = "ggx";
  std::vector<double> alpha{0.1};
  std::vector<double> slope{0, 0};
  std::vector<double> footprint{0, 0};
  std::string precision = "double";
  std::vector<std::string> params;
  bool json = false;
};

void RequireFinite(const std::vector<double>& values, const char* option) {
  for (double v : values)
    if (!std::isfinite(v)) throw UsageError(std::string(option) + " must be finite, got " + NumberText(v));
}

// The core takes finite inputs only: a value that does not fit the evaluation
// precision would reach it as Inf (and come out as NaN). `factor` is what
// Evaluate multiplies the value by in that precision (the footprint's 2).
void RequireRepresentable(const std::vector<double>& values, const char* option, const std::string& precision,
                          double factor = 1) {
  const bool in_float = precision == "float";
  const double largest = in_float ? double(std::numeric_limits<float>::max()) : std::numeric_limits<double>::max();
  for (double v : values) {
    const bool fits = in_float ? std::isfinite(float(factor) * float(v)) : std::isfinite(factor * v);
    if (!fits)
      throw UsageError(std::string(option) + " " + NumberText(v) + " is out of range for --precision " + precision +
                       " (" + (factor == 1 ? "" : NumberText(factor) + " x ") + "|value| must be at most " +
                       NumberText(largest) + ")");
  }
}

// The footprint (FX, FY) is the half-side pair of the slope-space rectangle.
// Screen derivatives are built so that every variant sees the same footprint:
// d hpp / dx = (2 FX, 0), d hpp / dy = (0, 2 FY) give rect half-sides exactly
// (FX, FY); normal-based variants see dn/dx = (2 FX, 0, 0), dn/dy = (0, 2 FY, 0)
// (at normal incidence a normal tilt moves the slope-space half vector by the
// same amount, to first order).
template <class T>
shading::FilteredNdf<T> Evaluate(const shading::VariantInfo& info, shading::Ndf ndf, const NdfOptions& o,
                                 const shading::Params<double>& p) {
  shading::Footprint<T> f;
  T fx = T(o.footprint[0]), fy = T(o.footprint[1]);  // 2 fx is finite: RequireRepresentable
  f.hpp = {T(o.slope[0]), T(o.slope[1])};
  f.dhpp_dx = {T(2) * fx, T(0)};
  f.dhpp_dy = {T(0), T(2) * fy};
  f.dn_dx = {T(2) * fx, T(0), T(0)};
  f.dn_dy = {T(0), T(2) * fy, T(0)};
  f.dng_dx = f.dn_dx;
  f.dng_dy = f.dn_dy;
  shading::Params<T> pt{T(p.fp_max), T(p.fp_min_cap), T(p.sigma2), T(p.kappa)};
  glm::vec<2, T> alpha{T(o.alpha[0]), T(o.alpha.size() > 1 ? o.alpha[1] : o.alpha[0])};
  return shading::EvaluateVariant<T>(info.id, ndf, alpha, f, pt);
}

void Run(const NdfOptions& o) {
  const shading::VariantInfo* info = shading::FindVariant(o.variant);
  if (!info) throw UsageError("unknown variant '" + o.variant + "' (see `shimmer variants`)");
  auto ndf = shading::ParseNdf(o.ndf);
  if (!ndf) throw UsageError("--ndf must be ggx or beckmann, got '" + o.ndf + "'");
  if (info->ggx_only && *ndf != shading::Ndf::kGgx)
    throw UsageError("variant " + o.variant + " filters GGX only; use --ndf ggx");
  if (o.precision != "float" && o.precision != "double")
    throw UsageError("--precision must be float or double, got '" + o.precision + "'");
  RequireFinite(o.alpha, "--alpha");
  RequireFinite(o.slope, "--slope");
  RequireFinite(o.footprint, "--footprint");
  for (double a : o.alpha)
    if (!(a > 0)) throw UsageError("--alpha must be > 0, got " + NumberText(a));
  for (double f : o.footprint)
    if (f < 0) throw UsageError("--footprint half-sides must be >= 0, got " + NumberText(f));
  RequireRepresentable(o.alpha, "--alpha", o.precision);
  RequireRepresentable(o.slope, "--slope", o.precision);
  RequireRepresentable(o.footprint, "--footprint", o.precision, 2);

  std::vector<std::pair<std::string, double>> overrides;
  for (const std::string& p : o.params) overrides.push_back(ParseParamOption(p));
  // ResolveParams holds every parameter to ParamFields(), whose bounds are finite floats.
  const shading::Params<double> resolved = Take(shading::ResolveParams(*info, overrides));

  double slope_density = 0, density = 0, aex = 0, aey = 0;
  if (o.precision == "float") {
    auto r = Evaluate<float>(*info, *ndf, o, resolved);
    slope_density = r.slope_density, density = r.density, aex = r.alpha_eff.x, aey = r.alpha_eff.y;
  } else {
    auto r = Evaluate<double>(*info, *ndf, o, resolved);
    slope_density = r.slope_density, density = r.density, aex = r.alpha_eff.x, aey = r.alpha_eff.y;
  }

  nlohmann::json params = nlohmann::json::object();
  for (const shading::ParamInfo& p : info->params) params[std::string(p.name)] = shading::ParamValue(resolved, p.name);
  double ax = o.alpha[0], ay = o.alpha.size() > 1 ? o.alpha[1] : o.alpha[0];
  nlohmann::json out = {{"variant", o.variant},     {"ndf", o.ndf},
                        {"precision", o.precision}, {"alpha", {ax, ay}},
                        {"slope", o.slope},         {"footprint", o.footprint},
                        {"params", params},         {"slope_density", slope_density},
                        {"density", density}};
  if (info->widens_roughness) out["alpha_eff"] = {aex, aey};
  if (o.json) {
    std::cout << out.dump() << "\n";
    return;
  }
  std::printf("variant        %s (%s, %s)\n", o.variant.c_str(), o.ndf.c_str(), o.precision.c_str());
  std::printf("slope_density  %.9g\n", slope_density);
  std::printf("density        %.9g\n", density);
  if (info->widens_roughness) std::printf("alpha_eff      %.9g %.9g\n", aex, aey);
}

}  // namespace

void AddNdfCommand(CLI::App& app) {
  auto o = std::make_shared<NdfOptions>();
  CLI::App* cmd = app.add_subcommand("ndf", "Evaluate a variant's filtered NDF at one slope (CPU, float or double)");
  cmd->add_option("--variant", o->variant, "Variant name (see `shimmer variants`)")->capture_default_str();
  cmd->add_option("--ndf", o->ndf, "Microfacet distribution: ggx or beckmann")->capture_default_str();
  cmd->add_option("--alpha", o->alpha, "Roughness alpha, or AX AY for anisotropic")->expected(1, 2);
  cmd->add_option("--slope", o->slope, "Slope-space half vector X Y (h.xy / h.z)")->expected(2);
  cmd->add_option("--footprint", o->footprint,
                  "Slope-space footprint half-sides FX FY; normal-based variants see dn/dx = (2FX,0,0), "
                  "dn/dy = (0,2FY,0)")
      ->expected(2);
  cmd->add_option("--precision", o->precision, "float or double")->capture_default_str();
  cmd->add_option("--param", o->params, "Variant parameter name=value (repeatable)");
  cmd->add_flag("--json", o->json, "Print one JSON object");
  cmd->callback([o] { Run(*o); });
}

}  // namespace shimmer::cli
