// The shading core seen from C++: the GLSL filter math of shading/glsl,
// compiled for float and double, plus the variant catalogue.
#pragma once

#include <glm/glm.hpp>

#include <cmath>

#include "shimmer/core/result.h"
#include "shimmer/shading/variant_table.h"  // Params<T>, generated from shading/variant_table.json

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace shimmer::shading {

// A kernel's static instruction counts by the unit they need
// (CountInstructions, spirv_compiler.h): a device-independent cost. A vector
// operation counts once, a loop body once.
struct InstructionCensus {
  int alu = 0, transcendental = 0, memory = 0, control = 0;
  int Total() const { return alu + transcendental + memory + control; }
};

// kGlints: Zirr and Kaplanyan's biscale glints (glints.glsl), alpha its
// microdetails' Beckmann slopes.
enum class Ndf { kGgx = 0, kBeckmann = 1, kBlinnPhong = 2, kGlints = 3 };
// Blinn-Phong power <-> roughness, alpha^2 = 2 / (s + 2) (Walter et al. 2007).
inline double BlinnPhongAlpha(double power) { return std::sqrt(2 / (power + 2)); }
inline double BlinnPhongPower(double alpha) { return 2 / (alpha * alpha) - 2; }

std::optional<Ndf> ParseNdf(std::string_view name);
std::string_view NdfName(Ndf ndf);

template <class T>
struct Footprint {
  glm::vec<2, T> hpp{0};
  glm::vec<2, T> dhpp_dx{0};
  glm::vec<2, T> dhpp_dy{0};
  glm::vec<3, T> n{0, 0, 1};
  glm::vec<3, T> dn_dx{0};
  glm::vec<3, T> dn_dy{0};
  glm::vec<3, T> dng_dx{0};
  glm::vec<3, T> dng_dy{0};
  // Screen derivatives of the projected half vector h.xy (tk19-forward).
  // The renderer differences h.xy across the quad or chains the analytic
  // slope derivatives; WithChainedProjection does the latter.
  glm::vec<2, T> dh_dx{0};
  glm::vec<2, T> dh_dy{0};
};

// f with dh_dx, dh_dy from its slope derivatives by the chain rule, as an
// analytic footprint has them: the shading core's projectedHalfVectorChange
// (variants.glsl), slope and derivatives capped as the core caps them.
template <class T>
Footprint<T> WithChainedProjection(Footprint<T> f);

template <class T>
struct FilteredNdf {
  T slope_density = 0;
  T density = 0;
  glm::vec<2, T> alpha_eff{0};
};

// Evaluates variant `id` (VariantInfo::id) through the compiled GLSL.
template <class T>
FilteredNdf<T> EvaluateVariant(int id, Ndf ndf, glm::vec<2, T> alpha, const Footprint<T>& footprint,
                               const Params<T>& params);

// Plain NDF and rectangle means, for tests and tools.
template <class T>
T SlopeDensity(Ndf ndf, glm::vec<2, T> slope, glm::vec<2, T> alpha);
template <class T>
T GgxRectMeanSeed(glm::vec<2, T> centre, glm::vec<2, T> alpha, glm::vec<2, T> half_sides);
template <class T>
T GgxRectMeanStable(glm::vec<2, T> centre, glm::vec<2, T> alpha, glm::vec<2, T> half_sides);
// Footprint mean of the solid-angle GGX density P22(s) (1 + |s|^2)^2 (k16-ggx-rect-jacobian).
template <class T>
T GgxRectMeanJacobian(glm::vec<2, T> centre, glm::vec<2, T> alpha, glm::vec<2, T> half_sides);

// --- Pixel oracle ------------------------------------------------------------
// The renderer's per-pixel computation (scene.glsl, pixel.glsl) run in double
// on the CPU: the oracle the GPU frames are compared against.

enum class DerivativeSource { kAnalytic = 0, kQuadFine = 1, kQuadCoarse = 2 };

struct CameraDesc {
  glm::dvec3 pos{0, 0, 5};
  glm::dvec3 fwd{0, 0, -1};  // orthonormal frame
  glm::dvec3 right{1, 0, 0};
  glm::dvec3 up{0, 1, 0};
  double tan_half_fov_y = 0.4;
  int width = 64;
  int height = 64;
};

// pixel.glsl's LIGHT_*. kSg: a distant spherical-Gaussian light (seed 004)
// amplitude * exp(sharpness * (axis . l - 1)).
enum class LightType { kDirectional = 0, kSphere = 1, kSg = 2 };
struct LightDesc {
  LightType type = LightType::kDirectional;
  glm::dvec3 vec{0, 1, 0};       // unit direction towards the light, the sphere's centre, or the SG's axis
  glm::dvec3 radiance{1, 1, 1};  // irradiance at normal incidence, intensity, or the SG's amplitude (radiance)
  double radius = 0;             // sphere: radius; SG: sharpness lambda
  // Hard shadows: a ray from each shaded point towards the light (the
  // sphere's centre); directional and sphere lights only. Off, no kernel
  // traces one (SCENE_SHADOWS).
  bool shadows = false;
};
// "directional", "sphere", "sg".
std::string_view LightTypeName(LightType type);

struct MaterialDesc {
  Ndf ndf = Ndf::kGgx;
  glm::dvec2 alpha{0.1, 0.1};
  glm::dvec3 f0{0.04, 0.04, 0.04};
  glm::dvec3 albedo{0.5, 0.5, 0.5};
  // A glint material's local lobe (roughness of one microdetail) and its
  // microdetails per unit area; 0 for the smooth NDFs.
  double glint_alpha_l = 0;
  double glint_density = 0;
};

// --- Glints (glints.glsl) -------------------------------------------------------
// How a glint material is read: filtered over the footprint (glints-zk16),
// at the finest level at the point (none, each reference sample), the naive
// level-0 cell (glints-naive), the smooth global NDF (glints-smooth), and
// the three that count the footprint's microdetails by the binomial law:
// zk16's grids (glints-zk16-counting), Deliot and Belcour's anisotropic
// grids (glints-db23) and point microdetails (glints-points).
enum class GlintMode { kFiltered = 0, kPoint = 1, kNaive = 2, kSmooth = 3, kCounting = 4, kDb23 = 5, kPoints = 6 };

// World-scaled texture coordinates, their change per pixel, the surface
// area per unit uv area (pixel.glsl), and the slope-space half vector's
// change per pixel (read by kPoints only).
template <class T>
struct GlintFootprint {
  glm::vec<2, T> uv{0};
  glm::vec<2, T> duvdx{0};
  glm::vec<2, T> duvdy{0};
  T area_scale = 1;
  glm::vec<2, T> dhppdx{0};
  glm::vec<2, T> dhppdy{0};
};

// A glint material's (material.ndf == kGlints) slope and solid-angle density at hpp.
template <class T>
FilteredNdf<T> EvaluateGlints(GlintMode mode, const MaterialDesc& material, glm::vec<2, T> hpp,
                              const GlintFootprint<T>& footprint);
// The microdetails of the footprint that reflect at hpp (count), out of its
// total N; the slope density is count / (total bin_area). For the modes that
// blend draws (kFiltered, kPoint, kNaive) and for kSmooth, the count their
// density stands for: slope_density total bin_area.
template <class T>
struct GlintCount {
  T count = 0;
  T total = 0;
  T bin_area = 0;
};
template <class T>
GlintCount<T> CountGlints(GlintMode mode, const MaterialDesc& material, glm::vec<2, T> hpp,
                          const GlintFootprint<T>& footprint);
// The process's draw for a cell of n microdetails in expectation (floor(n)
// or floor(n) + 1 by the uniform u2), each reflecting with probability p:
// Binomial(N, p) by the uniform u, monotone in u.
template <class T>
T GlintBinomial(T n, T p, T u, T u2);
// P(lo <= X <= hi) for X with Beckmann's one-axis slope marginal of roughness alpha.
template <class T>
T GlintInterval(T lo, T hi, T alpha);

struct PixelOracle {
  bool hit = false;
  int prim = -1;
  double depth = 0;  // distance from the eye along the ray
  glm::dvec3 normal{0};
  glm::dvec2 hpp{0};
  glm::dvec3 specular{0};
  glm::dvec3 diffuse{0};
  glm::dvec2 alpha_eff{0};
  glm::dvec2 footprint{0};
  Footprint<double> derivatives;
};

// Shades the centre of pixel `px` as the kernel does; `scene_words` is the
// packed scene uploaded to the GPU (see scene.glsl for the layout).
PixelOracle ShadePixel(std::span<const glm::vec4> scene_words, const CameraDesc& camera, const LightDesc& light,
                       const MaterialDesc& material, int variant, DerivativeSource derivatives,
                       const Params<double>& params, glm::ivec2 px);

// The nearest primitive along the ray through sub-pixel position `offset`
// ([0,1]^2) of pixel px, found two ways: by the full BVH walk (traceScene) and
// by the pixel's candidate list (traceCandidates), which the reference kernel
// uses. In float, as on the GPU. `candidates` above the kernel's limit
// (kPixelCandidates, or kMeshPixelCandidates for a scene with meshes) means
// the kernel walks the BVH for each sample of that pixel.
struct PixelTraceCheck {
  int scene_prim = -1;
  float scene_t = 0;
  int candidate_prim = -1;
  float candidate_t = 0;
  int candidates = 0;
};
inline constexpr int kPixelCandidates = 4;  // PIXEL_CANDIDATES of scene.glsl, a kernel without meshes
inline constexpr int kMeshPixelCandidates = 8;  // PIXEL_CANDIDATES of a kernel with meshes (and of this oracle)

// SCENE_* of scene.glsl: bits of the mask of primitive kinds a scene holds,
// which specialises the kernel (shading_glsl.cpp checks that they agree).
inline constexpr int kSceneSpheres = 1;
inline constexpr int kSceneCapsules = 2;
inline constexpr int kScenePlanes = 4;
inline constexpr int kSceneBumps = 8;  // planes with a normal pattern
inline constexpr int kSceneNormalMaps = 16;
inline constexpr int kSceneMeshes = 32;
inline constexpr int kSceneShadows = 64;  // the light casts shadows (LightDesc::shadows), not a primitive kind
inline constexpr int kSceneRoughnessMaps = 128;  // meshes with a roughness texture
inline constexpr int kAllSceneFeatures =
    kSceneSpheres | kSceneCapsules | kScenePlanes | kSceneBumps | kSceneNormalMaps | kSceneMeshes | kSceneRoughnessMaps;
// --- Normal maps (normal_map.glsl, scene.glsl), in double ---------------------

// Primitive `prim`'s uv at point p, its geometric tangent frame (t, b, n)
// and the gradients of u and v along the surface.
struct SurfaceUvFrame {
  glm::dvec2 uv{0};
  glm::dvec3 t{0}, b{0}, n{0};
  glm::dvec3 du{0}, dv{0};
  double u_period = 0;
};
SurfaceUvFrame SurfaceUvFrameAt(std::span<const glm::vec4> scene_words, int prim, glm::dvec3 p);

// What normal-map filter `nmf` (NMF_* of normal_map.glsl) reads from the map
// of primitive `prim` at uv with the uv footprint (duv_dx, duv_dy):
// E[n] (xyz) and f_t (w), B, and M = (E[tx^2], E[ty^2], E[tx ty]).
struct NormalMapRead {
  glm::dvec4 mean_normal_ft{0};
  glm::dvec2 b{0};
  glm::dvec3 m{0};
};
NormalMapRead ReadNormalMap(std::span<const glm::vec4> scene_words, int prim, int nmf, glm::dvec2 uv,
                            glm::dvec2 duv_dx, glm::dvec2 duv_dy);
// The tangent-space normal and the widened roughness filter `nmf` makes of `read`.
glm::dvec3 NormalMapFilterNormal(int nmf, const NormalMapRead& read);
// Per tangent axis (LEAN: the diagonal of its covariance).
glm::dvec2 NormalMapFilterAlpha(int nmf, const NormalMapRead& read, glm::dvec2 alpha, double scale = 1);
// The lobe the renderer shades: roughness along axes turned by `angle` from
// the tangent (LEAN: its covariance's eigenvectors; 0 for the others).
struct NormalMapFilterLobe {
  glm::dvec2 alpha{0};
  double angle = 0;
};
NormalMapFilterLobe NormalMapLobe(int nmf, const NormalMapRead& read, glm::dvec2 alpha, double scale = 1);

PixelTraceCheck TracePixelBothWays(std::span<const glm::vec4> scene_words, int scene_features, const CameraDesc& camera,
                                   glm::ivec2 px, glm::dvec2 offset);

// --- Variant catalogue ------------------------------------------------------

struct ParamInfo {
  std::string_view name;
  double default_value;
  std::string_view meaning;
};

// One entry of shading/variant_table.json (its "about" says what each field
// means).
struct VariantInfo {
  std::string_view name;
  int id;  // VARIANT_* (+ NMF_STRIDE times NMF_*) of the generated variant_table.glsl
  std::string_view summary;
  std::string_view source;
  std::vector<ParamInfo> params;
  bool widens_roughness = false;
  bool ggx_only = false;
  bool glints = false;           // shades glint materials (glints.glsl), and only those
  bool reads_footprint = false;  // its pixels read screen-space derivatives
  bool sg_light = false;         // shades SG lights only (seed 004's warps)
  bool smooth_limit = false;     // a glint material's limit without sparkles (D_g): never its pick
};

std::span<const VariantInfo> Variants();
// A catalogue entry, or a combination GEOMETRIC+NORMALMAP of a geometric
// filter and a normal-map filter ("tk19+toksvig"), made on first use and
// kept for the process (the pointer stays valid).
const VariantInfo* FindVariant(std::string_view name);
// Variant ids: a geometric filter (VARIANT_* < kNormalMapFilterStride) plus
// kNormalMapFilterStride times a normal-map filter (NMF_*).
inline int GeometricVariantId(int id) { return id % kNormalMapFilterStride; }
inline int NormalMapFilterId(int id) { return id / kNormalMapFilterStride; }
// Whether the variant filters a normal map (and so needs a scene that has one).
inline bool FiltersNormalMap(const VariantInfo& info) { return NormalMapFilterId(info.id) != 0; }
// Seed 004's SG and ASG warps shade SG lights only; every other variant
// shades any light.
inline bool NeedsSgLight(const VariantInfo& info) { return info.sg_light; }
// Why the variant cannot shade a material of this NDF, or nothing: glint
// variants need a glint material, which takes none (and supersample-N, its
// samples being none's) and the glint variants only.
std::optional<std::string> MaterialMismatch(const VariantInfo& info, Ndf ndf);
// Whether the variant's result depends on the shading footprint (none and the
// unfiltered SG warps do not: one derivative source is enough for them).
inline bool ReadsFootprint(const VariantInfo& info) { return info.reads_footprint; }

// The variant parameters, named once: what a variant may read, and the
// values it accepts.
struct ParamField {
  std::string_view name;
  double Params<double>::*member;
  double lo, hi;  // accepted: [lo, hi], finite
  std::string_view meaning;
};
std::span<const ParamField> ParamFields();
const ParamField* FindParamField(std::string_view name);
// The value of the parameter called `name` (ParamFields()).
double ParamValue(const Params<double>& params, std::string_view name);
// Empty Status when `value` is accepted for `name`; else the error names the
// parameter, the value and the accepted range.
Status ValidateParam(std::string_view name, double value);

// Defaults of `info` overridden by `overrides` (name, value); the error names
// an unknown parameter or a value out of range.
Result<Params<double>> ResolveParams(const VariantInfo& info,
                                     std::span<const std::pair<std::string, double>> overrides);

// The GLSL sources of the shading core, by file name (core.glsl first).
std::span<const std::pair<std::string_view, std::string_view>> GlslSources();

}  // namespace shimmer::shading

namespace shimmer::shading {

// --- Names parsed from text, once ----------------------------------------------

// "quad" (= "quad-fine"), "quad-coarse", "analytic".
std::optional<DerivativeSource> ParseDerivativeSource(std::string_view name);
// The canonical name: "quad", "quad-coarse" or "analytic".
std::string_view DerivativeSourceName(DerivativeSource source);
inline constexpr std::string_view kDerivativeSourceList = "quad, quad-coarse or analytic";

// What a variant name denotes: a catalogue entry, or supersample-N (N x N
// stratified samples of `none`, the equal-time brute-force baseline).
struct VariantName {
  enum class Kind { kCatalogue, kSupersample };
  Kind kind = Kind::kCatalogue;
  const VariantInfo* info = nullptr;  // the catalogue entry; `none` for supersample-N
  int spp_n = 1;                      // N of supersample-N, 1 otherwise
  // True when the pixels read screen-space derivatives: not `none`, not supersample-N.
  bool reads_derivatives() const { return kind == Kind::kCatalogue && ReadsFootprint(*info); }
};
inline constexpr int kMaxSupersampleN = 64;
// The error names `name` and says what would be accepted.
Result<VariantName> ParseVariantName(std::string_view name);

}  // namespace shimmer::shading
