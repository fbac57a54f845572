// `shimmer ndf`: evaluates one variant's filtered NDF at one slope, on the CPU
// in float or double, or on the Vulkan device in float (a user's variant file
// always: its code exists only as GLSL), through the same GLSL the renderer runs.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "shimmer/core/number_text.h"
#include "shimmer/renderer/renderer.h"
#include "shimmer/shading/shading.h"
#include "shimmer/shading/user_variant.h"

namespace shimmer::cli {

namespace {

struct NdfOptions {
  std::string variant = "none";
  std::string ndf = "ggx";
  std::vector<double> alpha{0.1};
  std::vector<double> slope{0, 0};
  std::vector<double> footprint{0, 0};
  std::string precision;  // default: double on the CPU, float on the device
  std::string variant_file;
  bool on_device = false;
  std::string device;
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
// same amount, to first order); tk19-forward sees the projected half vector's
// derivatives chained from the slope's, as an analytic footprint has them.
template <class T>
shading::Footprint<T> FootprintOf(const NdfOptions& o) {
  shading::Footprint<T> f;
  T fx = T(o.footprint[0]), fy = T(o.footprint[1]);  // 2 fx is finite: RequireRepresentable
  f.hpp = {T(o.slope[0]), T(o.slope[1])};
  f.dhpp_dx = {T(2) * fx, T(0)};
  f.dhpp_dy = {T(0), T(2) * fy};
  f.dn_dx = {T(2) * fx, T(0), T(0)};
  f.dn_dy = {T(0), T(2) * fy, T(0)};
  f.dng_dx = f.dn_dx;
  f.dng_dy = f.dn_dy;
  return shading::WithChainedProjection(f);
}

template <class T>
shading::FilteredNdf<double> Evaluate(const shading::VariantInfo& info, shading::Ndf ndf, const NdfOptions& o,
                                      const shading::Params<double>& p) {
  const auto pt = shading::ParamsCast<T>(p);
  glm::vec<2, T> alpha{T(o.alpha[0]), T(o.alpha.size() > 1 ? o.alpha[1] : o.alpha[0])};
  const auto r = shading::EvaluateVariant<T>(info.id, ndf, alpha, FootprintOf<T>(o), pt);
  return {double(r.slope_density), double(r.density), {double(r.alpha_eff.x), double(r.alpha_eff.y)}};
}

void Run(const NdfOptions& o) {
  const bool user = !o.variant_file.empty();
  const bool on_device = user || o.on_device;
  const std::string precision = !o.precision.empty() ? o.precision : on_device ? "float" : "double";
  if (precision != "float" && precision != "double")
    throw UsageError("--precision must be float or double, got '" + precision + "'");
  if (on_device && precision != "float")
    throw UsageError(std::string(user ? "--variant-file" : "--on-device") +
                     " evaluates on the Vulkan device, in float: --precision double is the CPU oracle's");
  const shading::VariantInfo* info = user ? nullptr : shading::FindVariant(o.variant);
  if (!user && !info) throw UsageError("unknown variant '" + o.variant + "' (see `shimmer variants`)");
  auto ndf = shading::ParseNdf(o.ndf);
  if (!ndf) throw UsageError("--ndf must be ggx or beckmann, got '" + o.ndf + "'");
  if (info && info->glints)
    throw UsageError("variant " + o.variant +
                     " reads a glint material's texture-space process, not a slope-space footprint; render it "
                     "(docs/glints.md)");
  if (info && info->ggx_only && *ndf != shading::Ndf::kGgx)
    throw UsageError("variant " + o.variant + " filters GGX only; use --ndf ggx");
  RequireFinite(o.alpha, "--alpha");
  RequireFinite(o.slope, "--slope");
  RequireFinite(o.footprint, "--footprint");
  for (double a : o.alpha)
    if (!(a > 0)) throw UsageError("--alpha must be > 0, got " + NumberText(a));
  for (double f : o.footprint)
    if (f < 0) throw UsageError("--footprint half-sides must be >= 0, got " + NumberText(f));
  RequireRepresentable(o.alpha, "--alpha", precision);
  RequireRepresentable(o.slope, "--slope", precision);
  RequireRepresentable(o.footprint, "--footprint", precision, 2);

  std::vector<std::pair<std::string, double>> overrides;
  for (const std::string& p : o.params) overrides.push_back(ParseParamOption(p));
  // Parameters are held to their ranges, whose bounds are finite floats.
  shading::Params<double> resolved;
  nlohmann::json params = nlohmann::json::object();
  std::shared_ptr<const shading::UserVariant> file;
  if (user) {
    file = std::make_shared<const shading::UserVariant>(Take(shading::LoadUserVariant(o.variant_file)));
    const shading::UserParams values = Take(shading::ResolveUserParams(*file, overrides));
    resolved = values.values;
    for (const auto& [name, value] : values.shown) params[name] = value;
  } else {
    resolved = Take(shading::ResolveParams(*info, overrides));
    for (const shading::ParamInfo& p : info->params) params[std::string(p.name)] = shading::ParamValue(resolved, p.name);
  }

  shading::FilteredNdf<double> r;
  std::string device;
  if (on_device) {
    render::NdfProbe probe;
    probe.variant_id = info ? info->id : 0;
    probe.user = file;
    probe.ndf = *ndf;
    probe.alpha = {o.alpha[0], o.alpha.size() > 1 ? o.alpha[1] : o.alpha[0]};
    probe.footprint = FootprintOf<double>(o);
    probe.params = resolved;
    probe.device = o.device;
    r = Take(render::ProbeNdf(probe));
  } else {
    r = precision == "float" ? Evaluate<float>(*info, *ndf, o, resolved) : Evaluate<double>(*info, *ndf, o, resolved);
  }

  // A user variant's alpha_eff is shown always: nothing says whether it widens roughness.
  const bool show_alpha = !info || info->widens_roughness;
  const std::string name = user ? o.variant_file : o.variant;
  double ax = o.alpha[0], ay = o.alpha.size() > 1 ? o.alpha[1] : o.alpha[0];
  nlohmann::json out = {{"variant", name},        {"ndf", o.ndf},
                        {"precision", precision}, {"alpha", {ax, ay}},
                        {"slope", o.slope},       {"footprint", o.footprint},
                        {"params", params},       {"slope_density", r.slope_density},
                        {"density", r.density}};
  if (show_alpha) out["alpha_eff"] = {r.alpha_eff.x, r.alpha_eff.y};
  if (o.json) {
    std::cout << out.dump() << "\n";
    return;
  }
  std::printf("variant        %s (%s, %s%s)\n", name.c_str(), o.ndf.c_str(), precision.c_str(),
              on_device ? ", on the device" : "");
  std::printf("slope_density  %.9g\n", r.slope_density);
  std::printf("density        %.9g\n", r.density);
  if (show_alpha) std::printf("alpha_eff      %.9g %.9g\n", r.alpha_eff.x, r.alpha_eff.y);
}

}  // namespace

void AddNdfCommand(CLI::App& app) {
  auto o = std::make_shared<NdfOptions>();
  CLI::App* cmd = app.add_subcommand("ndf", "Evaluate a variant's filtered NDF at one slope (CPU float or double, or the device)");
  cmd->add_option("--variant", o->variant, "Variant name (see `shimmer variants`)")->capture_default_str();
  cmd->add_option("--variant-file", o->variant_file,
                  "A user variant's GLSL file (docs/variants.md), evaluated on the Vulkan device in float");
  cmd->add_flag("--on-device", o->on_device, "Evaluate a built-in variant on the Vulkan device (float) too");
  cmd->add_option("--device", o->device, "Vulkan device name substring (with --variant-file or --on-device)");
  cmd->add_option("--ndf", o->ndf, "Microfacet distribution: ggx or beckmann")->capture_default_str();
  cmd->add_option("--alpha", o->alpha, "Roughness alpha, or AX AY for anisotropic")->expected(1, 2);
  cmd->add_option("--slope", o->slope, "Slope-space half vector X Y (h.xy / h.z)")->expected(2);
  cmd->add_option("--footprint", o->footprint,
                  "Slope-space footprint half-sides FX FY; normal-based variants see dn/dx = (2FX,0,0), "
                  "dn/dy = (0,2FY,0)")
      ->expected(2);
  cmd->add_option("--precision", o->precision, "float or double (default: double on the CPU, float on the device)");
  cmd->add_option("--param", o->params, "Variant parameter name=value (repeatable)");
  cmd->add_flag("--json", o->json, "Print one JSON object");
  cmd->callback([o, cmd] {
    RequireOneFilter(*cmd, o->variant, o->variant_file);
    Run(*o);
  });
}

}  // namespace shimmer::cli
