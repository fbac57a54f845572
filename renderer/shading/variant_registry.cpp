// The variant catalogue: names, parameters with defaults, and sources, as
// listed by `shimmer variants` and accepted by specs and `shimmer ndf`.
#include <cmath>
#include <deque>
#include <mutex>
#include <optional>
#include <string>

#include "shimmer/renderer/shading.h"

namespace shimmer::shading {

namespace {

constexpr double kInvTwoPi = 0.15915494309189533577;

const ParamInfo kFpMax1{"fp_max", 1.0,
                        "upper clamp on the slope-space footprint half-sides (seed 000: \"usually 1.0\")"};
const ParamInfo kNmScale1{"nm_scale", 1.0, "scale on the roughness variance the normal-map filter adds (1: as published)"};

std::vector<VariantInfo> BuildCatalogue() {
  return {
      {"none", 0, "point-sampled NDF, no filtering", "baseline", {}, false, false},
      {"vlachos15",
       1,
       "perceptual roughness clamped from below by sat(S pow(max(|dn/dx|^2, |dn/dy|^2), E) + B) of the geometric "
       "normal; Vlachos' constants S = 1, B = 0, E = 0.333",
       "Vlachos, Advanced VR Rendering, GDC 2015 (cited in seed 000); Valve's The Lab renderer; the constants as "
       "Unreal's Normal Curvature to Roughness exposes them",
       {{"curvature_scale", 1.0, "S: scale on the curvature term (Unreal: Normal Curvature to Roughness scale)"},
        {"curvature_bias", 0.0, "B: bias added after the scale"},
        {"curvature_exponent", 0.333, "E: exponent on max(|dn/dx|^2, |dn/dy|^2)"}},
       true,
       false},
      {"toksvig-quad",
       2,
       "Toksvig: alpha^2 += 2 (1 - |Na|) / |Na|, Na the mean normal of the 2x2 quad rebuilt from dn/dx, dn/dy",
       "Toksvig 2004 via seed 003 (Hill, Specular showdown) and seed 000",
       {},
       true,
       false},
      {"k16-beckmann-rect",
       3,
       "axis-aligned slope-space footprint rect, fp = (|dx hpp| + |dy hpp|) / 2 clamped to fp_max, alpha^2 += 2 fp^2; "
       "exact Gaussian convolution for Beckmann, the same widening applied to GGX",
       "seed 000 (Kaplanyan, Stable Specular Highlights, GDC 2016)",
       {kFpMax1},
       true,
       false},
      {"k16-beckmann-parallelogram",
       4,
       "full footprint parallelogram: R' = R + 2 U U^T, U = sqrt(sigma2) times the per-pixel hpp derivatives "
       "(Gaussian pixel filter of variance sigma2; 0.25 is 0.5 px, 1 the slide's bare U), anisotropic and rotated",
       "seed 000",
       {{"sigma2", 0.25, "screen-space variance of the pixel filter (1: the slide's bare U = dh/duv)"}},
       true,
       false},
      {"k16-ggx-rect",
       5,
       "closed-form mean of GGX over the footprint rect as published, fp clamped to [min(alpha, fp_min_cap), fp_max], "
       "Jacobian 1 / max(1e-3, h.z^4)",
       "seed 000",
       {kFpMax1, {"fp_min_cap", 0.1, "fp_min = min(alpha, fp_min_cap) against the formula's instability (seed 000)"}},
       false,
       true},
      {"k16-ggx-rect-stable",
       6,
       "the same rect mean, evaluated without cancellation (closed form in one axis, 8-point Gauss-Legendre on a "
       "tangent "
       "substitution in the other): no fp_min, relative error <= 1e-4 in float",
       "ours, after seed 000",
       {kFpMax1},
       false,
       true},
      {"k16-ggx-rect-jacobian",
       13,
       "footprint mean of D = P22 (1 + |s|^2)^2 over the same rect, the Jacobian inside the integral instead of "
       "1 / h.z^4 of the centre; closed form in one axis, Gauss-Legendre on a tangent or sinh substitution in the "
       "other, "
       "relative error <= 1e-4 in float",
       "ours, after seed 000",
       {kFpMax1},
       false,
       true},
      {"k16-ggx-proxy",
       7,
       "Beckmann proxy for GGX: alpha^2 += 2 fp^2 with the rect footprint clamped to 0.7, GGX evaluated with the "
       "widened "
       "alpha",
       "seed 001 (Kaplanyan et al., Specular Antialiasing slides)",
       {{"fp_max", 0.7, "upper clamp on the footprint half-sides (seed 001 uses 0.7)"}},
       true,
       true},
      {"tk19",
       8,
       "alpha'^2 = sat(alpha^2 + min(2 sigma2 S, kappa)), S = |dn/dx|^2 + |dn/dy|^2 of the shading normal",
       "Tokuyoshi and Kaplanyan, Improved Geometric Specular Antialiasing, I3D 2019",
       {{"sigma2", 0.25, "screen-space variance of the filtering kernel"},
        {"kappa", 0.18, "clamp on the kernel roughness"}},
       true,
       false},
      {"tk19-forward",
       21,
       "the paper's forward filter: kernel 2 sigma2 (dx dx^T + dy dy^T) from the screen derivatives of the projected "
       "half vector h.xy (not the slope), its eigenvalues clamped to kappa, added to the roughness matrix: "
       "non-axis-aligned",
       "Tokuyoshi and Kaplanyan, Improved Geometric Specular Antialiasing, I3D 2019 (forward rendering)",
       {{"sigma2", 0.25, "screen-space variance of the filtering kernel"},
        {"kappa", 0.18, "clamp on the kernel roughness (on its eigenvalues)"}},
       true,
       false},
      {"tk19-forward-rect",
       22,
       "the paper's axis-aligned forward filter: alpha'^2 = sat(alpha^2 + min(2 sigma2 b^2, kappa)) per axis, "
       "b = |dx h.xy| + |dy h.xy| the bounding rectangle of the projected half vector's derivatives",
       "Tokuyoshi and Kaplanyan, Improved Geometric Specular Antialiasing, I3D 2019 (forward rendering)",
       {{"sigma2", 0.25, "screen-space variance of the filtering kernel"},
        {"kappa", 0.18, "clamp on the kernel roughness"}},
       true,
       false},
      {"tk21",
       9,
       "projected space: p = alpha^2 / (1 - alpha^2), p' = p + min(sigma2 S, kappa), alpha'^2 = p' / (1 + p')",
       "Tokuyoshi and Kaplanyan, Stable Geometric Specular Antialiasing with Projected-Space NDF Filtering, JCGT 2021",
       {{"sigma2", kInvTwoPi, "screen-space variance of the kernel (1 / 2 pi, the authors' listing)"},
        {"kappa", 0.18, "clamp on the kernel roughness"}},
       true,
       false},
      {"filament",
       10,
       "tk19 form on the geometric normal with Filament's defaults",
       "Filament (google/filament)",
       {{"sigma2", 0.15, "specularAntiAliasingVariance"}, {"kappa", 0.2, "specularAntiAliasingThreshold"}},
       true,
       false},
      {"unity-hdrp",
       11,
       "tk19 form on the geometric normal, HDRP Lit defaults, threshold used squared",
       "Unity HDRP (ProjectedSpaceGeometricNormalFiltering)",
       {{"sigma2", 0.1, "specular AA screen-space variance"}, {"kappa", 0.04, "threshold 0.2, squared by HDRP"}},
       true,
       false},
      {"godot",
       12,
       "tk19 constants, kernel added to alpha = r^2 instead of alpha^2 (Godot's quirk)",
       "Godot 4 (roughness limiter)",
       {{"sigma2", 0.25, "roughness_limiter_amount"}, {"kappa", 0.18, "roughness_limiter_limit"}},
       true,
       false},
      {"sg-warp",
       14,
       "SG lights only: the NDF as one SG, warped to the light domain (Wang et al. 2009), SG x SG inner product with "
       "the light, G2 and F at the lobe centre",
       "seed 004 (Pettineo, SG Series Part 4: SpecularTermSGWarp)",
       {},
       false,
       true},
      {"asg-warp",
       15,
       "SG lights only: the NDF SG warped to an anisotropic SG (Xu et al. 2013), ASG x SG convolution with the light, "
       "G2 and F at the lobe centre",
       "seed 004 (SpecularTermASGWarp)",
       {},
       false,
       true},
      {"sg-warp-k16",
       16,
       "sg-warp with the pixel footprint folded into the NDF's SG: alpha^2 += fp.x^2 + fp.y^2 (1 / lambda' = 1 / "
       "lambda + 1 / lambda_fp), fp the rect footprint clamped to fp_max",
       "ours: seed 004 filtered with seed 000's footprint",
       {kFpMax1},
       true,
       true},
      {"asg-warp-k16",
       17,
       "asg-warp with the same footprint folded into the NDF's SG before the warp",
       "ours: seed 004 filtered with seed 000's footprint",
       {kFpMax1},
       true,
       true},
      // Glint materials only (glints.glsl). `none` on a glint material shades
      // the finest level at the pixel centre, as each reference sample does.
      {"glints-zk16",
       18,
       "biscale glints filtered over the pixel footprint: texture-space power-of-two grids, one binomial draw per cell "
       "and slope bin, trilinear across levels, up to 16 probes along an anisotropic footprint",
       "seed 001 (Zirr and Kaplanyan, Real-time Rendering of Procedural Multiscale Materials, I3D 2016)",
       {},
       false,
       false,
       true},
      {"glints-naive",
       19,
       "the sparkle baseline: the level-0 cell holding the point and the slope bin holding h, whatever the footprint "
       "(the unstable case of seed 001's previous work)",
       "baseline (seed 001)",
       {},
       false,
       false,
       true},
      {"glints-smooth",
       20,
       "the global NDF D_g = D_m * D_l, Beckmann with alpha_g^2 = alpha^2 + alpha_l^2: what the glints average to in "
       "the distance, without sparkles",
       "seed 001 (biscale NDF)",
       {},
       false,
       false,
       true},
      // Normal-map filters (normal_map.glsl; scenes with a normal map only).
      // Each combines with a geometric filter as GEOMETRIC+NAME.
      {"nm-point",
       1 * kNormalMapFilterStride,
       "normal map at level 0, nearest texel: no mip maps, no filtering (the aliasing baseline)",
       "baseline (seed 003)",
       {},
       false,
       false},
      {"nm-mip",
       2 * kNormalMapFilterStride,
       "the mipped (trilinear, anisotropic) mean normal renormalised, roughness kept: bumps average away and the "
       "surface turns glossy in the distance",
       "baseline (seed 003)",
       {},
       false,
       false},
      {"toksvig",
       3 * kNormalMapFilterStride,
       "mipped normal, alpha^2 += 2 sigma^2 with sigma^2 = (1 - |Na|) / |Na| from the mean normal's length (the "
       "alpha form)",
       "Toksvig 2004 via seed 003 (Hill, Specular showdown)",
       {kNmScale1},
       true,
       false},
      {"toksvig-bp",
       4 * kNormalMapFilterStride,
       "seed 003's Blinn-Phong form: power f_t s, f_t = |Na| / (|Na| + s (1 - |Na|)), s = 2 / alpha^2 - 2",
       "seed 003",
       {kNmScale1},
       true,
       false},
      {"toksvig-map",
       5 * kNormalMapFilterStride,
       "Toksvig factor baked per mip level from a Gaussian-filtered level at power 100, converted with "
       "ft /= lerp(s / 100, 1, ft)",
       "seed 003 (Toksvig map)",
       {kNmScale1},
       true,
       false},
      {"lean",
       6 * kNormalMapFilterStride,
       "normal of the mean slope B, lobe covariance diag(alpha^2) + 2 (M - B B^T) on its eigenvectors (anisotropic, "
       "turned to the ridges)",
       "Olano and Baker, LEAN Mapping, I3D 2010 (seed 003)",
       {kNmScale1},
       true,
       false},
      {"clean",
       7 * kNormalMapFilterStride,
       "normal of B, one variance (E|t|^2 - |B|^2) / 2 per axis: LEAN without anisotropy",
       "Baker, CLEAN mapping, GDC 2011 (seed 003)",
       {kNmScale1},
       true,
       false},
      {"vmf",
       8 * kNormalMapFilterStride,
       "von Mises-Fisher fit of the mean normal, kappa = (3r - r^3) / (1 - r^2), alpha^2 += 2 / kappa",
       "Han et al., Frequency Domain Normal Map Filtering, SIGGRAPH 2007",
       {kNmScale1},
       true,
       false},
      {"unity-hdrp-nm",
       9 * kNormalMapFilterStride,
       "HDRP texture normal filtering: variance 0.25 / kappa capped at 0.03125, alpha^2 += 2 variance (4x less "
       "widening than vmf)",
       "Unity HDRP (TextureNormalVariance)",
       {kNmScale1},
       true,
       false},
  };
}

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
  info.params.insert(info.params.end(), nm->params.begin(), nm->params.end());
  return &info;
}

}  // namespace

std::span<const VariantInfo> Variants() {
  static const std::vector<VariantInfo> catalogue = BuildCatalogue();
  return catalogue;
}

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

bool NeedsSgLight(const VariantInfo& info) {
  const int g = GeometricVariantId(info.id);
  return g >= kFirstSgVariant && g <= kLastSgVariant;
}

bool ReadsFootprint(const VariantInfo& info) {
  return info.name != "none" && info.name != "sg-warp" && info.name != "asg-warp" && info.name != "nm-point" &&
         info.name != "glints-naive" && info.name != "glints-smooth";
}

std::optional<std::string> MaterialMismatch(const VariantInfo& info, Ndf ndf) {
  const bool glint_material = ndf == Ndf::kGlints;
  if (info.glints && !glint_material)
    return "variant " + std::string(info.name) +
           " shades glint materials only; use a glint material such as glints:0.3,local=0.03,density=1e4";
  if (glint_material && !info.glints && info.id != 0)
    return "a glint material takes none, supersample-N, glints-zk16, glints-naive or glints-smooth, not " +
           std::string(info.name);
  if (info.ggx_only && ndf != Ndf::kGgx) return "variant " + std::string(info.name) + " filters GGX only; use a ggx material";
  return std::nullopt;
}

}  // namespace shimmer::shading
