// The GLSL shading core compiled as C++, once per precision.
#include "shimmer/shading/sg.h"
#include "shimmer/shading/shading.h"

#include <glm/glm.hpp>

namespace shimmer::shading {
namespace {
// The scene the GLSL's sceneWord() reads in C++ (set by ShadePixel).
thread_local std::span<const glm::vec4> g_scene_words;
// SCENE_FEATURES of scene.glsl: every kind, except where a test specialises
// the core as the kernel does.
thread_local int g_scene_features = kAllSceneFeatures;
}  // namespace

#define SHIMMER_SCENE_WORDS
#define SHIMMER_SCENE_FEATURES
#define SHIMMER_MESHES  // the oracle traces every kind; SCENE_FEATURES picks
// The oracle shades every glint variant; a kernel compiles the counted ones
// only when it shades one (pipeline_cache.cpp).
#define SHIMMER_COUNTED_GLINTS
#define SCENE_FEATURES g_scene_features
namespace glsl_f32 {
using real = float;
#include "glsl_compat.h"
vec4 sceneWord(int i) {
  if (i < 0 || std::size_t(i) >= g_scene_words.size()) return vec4(0.0f);
  return g_scene_words[std::size_t(i)];
}
#include "core.glsl"
FilteredNdf variantAt(int variant, int ndf, vec2 alpha, ShadingFootprint f, VariantParams p) {
  return evalVariant(variant, ndf, alpha, f, p);
}
}  // namespace glsl_f32

namespace glsl_f64 {
using real = double;
#include "glsl_compat.h"
vec4 sceneWord(int i) {
  if (i < 0 || std::size_t(i) >= g_scene_words.size()) return vec4(0.0);
  return vec4(g_scene_words[std::size_t(i)]);
}
#include "core.glsl"
FilteredNdf variantAt(int variant, int ndf, vec2 alpha, ShadingFootprint f, VariantParams p) {
  return evalVariant(variant, ndf, alpha, f, p);
}
}  // namespace glsl_f64

static_assert(kMeshPixelCandidates == glsl_f32::PIXEL_CANDIDATES);  // the oracle compiles the mesh code
static_assert(int(GlintMode::kFiltered) == glsl_f32::GLINT_FILTERED && int(GlintMode::kPoint) == glsl_f32::GLINT_POINT &&
              int(GlintMode::kNaive) == glsl_f32::GLINT_NAIVE && int(GlintMode::kSmooth) == glsl_f32::GLINT_SMOOTH);
static_assert(int(GlintMode::kCounting) == glsl_f32::GLINT_COUNTING && int(GlintMode::kDb23) == glsl_f32::GLINT_DB23 &&
              int(GlintMode::kPoints) == glsl_f32::GLINT_POINTS);
static_assert(int(Ndf::kGlints) == glsl_f32::NDF_GLINTS);
static_assert(kNormalMapFilterStride == glsl_f32::NMF_STRIDE);
static_assert(int(LightType::kSg) == glsl_f32::LIGHT_SG && int(LightType::kSphere) == glsl_f32::LIGHT_SPHERE);
static_assert(kSceneSpheres == glsl_f32::SCENE_SPHERES && kSceneCapsules == glsl_f32::SCENE_CAPSULES &&
              kScenePlanes == glsl_f32::SCENE_PLANES && kSceneBumps == glsl_f32::SCENE_BUMPS &&
              kSceneNormalMaps == glsl_f32::SCENE_NORMAL_MAPS && kSceneMeshes == glsl_f32::SCENE_MESHES &&
              kSceneShadows == glsl_f32::SCENE_SHADOWS && kSceneRoughnessMaps == glsl_f32::SCENE_ROUGHNESS_MAPS);

namespace {

// The GLSL struct VariantParams (either precision) from Params, field by field
// as the table lists them.
template <class GlslParams, class T>
GlslParams GlslVariantParams(const Params<T>& params) {
  GlslParams p;
#define SHIMMER_COPY_PARAM(name) p.name = params.name;
  SHIMMER_VARIANT_PARAMS(SHIMMER_COPY_PARAM)
#undef SHIMMER_COPY_PARAM
  return p;
}

template <class T>
struct Glsl;
template <>
struct Glsl<float> {
  using ShadingFootprint = glsl_f32::ShadingFootprint;
  using VariantParams = glsl_f32::VariantParams;
  static auto Eval(int v, int ndf, glm::vec2 a, ShadingFootprint f, VariantParams p) {
    return glsl_f32::evalVariant(v, ndf, a, f, p);
  }
  static float Density(int ndf, glm::vec2 s, glm::vec2 a) { return glsl_f32::slopeDensity(ndf, s, a); }
  static glm::vec2 ProjectedChange(glm::vec2 s, glm::vec2 ds) { return glsl_f32::projectedHalfVectorChange(s, ds); }
  static float RectSeed(glm::vec2 c, glm::vec2 a, glm::vec2 f) { return glsl_f32::ggxRectMeanSeed(c, a, f); }
  static float RectStable(glm::vec2 c, glm::vec2 a, glm::vec2 f) { return glsl_f32::ggxRectMeanStable(c, a, f); }
  static float RectJacobian(glm::vec2 c, glm::vec2 a, glm::vec2 f) { return glsl_f32::ggxRectMeanJacobian(c, a, f); }
  using SG = glsl_f32::SG;
  using ASG = glsl_f32::ASG;
  static SG SgNdf(glm::vec3 n, float a) { return glsl_f32::distributionTermSG(n, a); }
  using SgShadingPoint = glsl_f32::SgShadingPoint;
  static glm::vec3 Perpendicular(glm::vec3 n) { return glsl_f32::perpendicularTo(n); }
  static float OneMinusExpNegOver(float y) { return glsl_f32::oneMinusExpNegOver(y); }
  using GlintMaterial = glsl_f32::GlintMaterial;
  using GlintFootprint = glsl_f32::GlintFootprint;
  static auto Glint(int mode, GlintMaterial g, glm::vec<2, float> hpp, GlintFootprint fp) {
    return glsl_f32::glintNdf(mode, g, hpp, fp);
  }
  static auto Count(int mode, GlintMaterial g, glm::vec<2, float> hpp, GlintFootprint fp) {
    return glsl_f32::glintCount(mode, g, hpp, fp);
  }
  static float Binomial(float n, float p, float u, float u2) { return glsl_f32::glintBinomial(n, p, u, u2); }
  static float Interval(float a, float b, float alpha) { return glsl_f32::glintInterval(a, b, alpha); }
};
template <>
struct Glsl<double> {
  using ShadingFootprint = glsl_f64::ShadingFootprint;
  using VariantParams = glsl_f64::VariantParams;
  static auto Eval(int v, int ndf, glm::dvec2 a, ShadingFootprint f, VariantParams p) {
    return glsl_f64::evalVariant(v, ndf, a, f, p);
  }
  static double Density(int ndf, glm::dvec2 s, glm::dvec2 a) { return glsl_f64::slopeDensity(ndf, s, a); }
  static glm::dvec2 ProjectedChange(glm::dvec2 s, glm::dvec2 ds) {
    return glsl_f64::projectedHalfVectorChange(s, ds);
  }
  static double RectSeed(glm::dvec2 c, glm::dvec2 a, glm::dvec2 f) { return glsl_f64::ggxRectMeanSeed(c, a, f); }
  static double RectStable(glm::dvec2 c, glm::dvec2 a, glm::dvec2 f) { return glsl_f64::ggxRectMeanStable(c, a, f); }
  static double RectJacobian(glm::dvec2 c, glm::dvec2 a, glm::dvec2 f) {
    return glsl_f64::ggxRectMeanJacobian(c, a, f);
  }
  using SG = glsl_f64::SG;
  using ASG = glsl_f64::ASG;
  static SG SgNdf(glm::dvec3 n, double a) { return glsl_f64::distributionTermSG(n, a); }
  using SgShadingPoint = glsl_f64::SgShadingPoint;
  static glm::dvec3 Perpendicular(glm::dvec3 n) { return glsl_f64::perpendicularTo(n); }
  static double OneMinusExpNegOver(double y) { return glsl_f64::oneMinusExpNegOver(y); }
  using GlintMaterial = glsl_f64::GlintMaterial;
  using GlintFootprint = glsl_f64::GlintFootprint;
  static auto Glint(int mode, GlintMaterial g, glm::vec<2, double> hpp, GlintFootprint fp) {
    return glsl_f64::glintNdf(mode, g, hpp, fp);
  }
  static auto Count(int mode, GlintMaterial g, glm::vec<2, double> hpp, GlintFootprint fp) {
    return glsl_f64::glintCount(mode, g, hpp, fp);
  }
  static double Binomial(double n, double p, double u, double u2) { return glsl_f64::glintBinomial(n, p, u, u2); }
  static double Interval(double a, double b, double alpha) { return glsl_f64::glintInterval(a, b, alpha); }
};

}  // namespace

template <class T>
Footprint<T> WithChainedProjection(Footprint<T> f) {
  f.dh_dx = Glsl<T>::ProjectedChange(f.hpp, f.dhpp_dx);
  f.dh_dy = Glsl<T>::ProjectedChange(f.hpp, f.dhpp_dy);
  return f;
}

template <class T>
FilteredNdf<T> EvaluateVariant(int id, Ndf ndf, glm::vec<2, T> alpha, const Footprint<T>& footprint,
                               const Params<T>& params) {
  typename Glsl<T>::ShadingFootprint f;
  f.hpp = footprint.hpp;
  f.dhpp_dx = footprint.dhpp_dx;
  f.dhpp_dy = footprint.dhpp_dy;
  f.dh_dx = footprint.dh_dx;
  f.dh_dy = footprint.dh_dy;
  f.n = footprint.n;
  f.dn_dx = footprint.dn_dx;
  f.dn_dy = footprint.dn_dy;
  f.dng_dx = footprint.dng_dx;
  f.dng_dy = footprint.dng_dy;
  const auto p = GlslVariantParams<typename Glsl<T>::VariantParams>(params);
  auto r = Glsl<T>::Eval(id, static_cast<int>(ndf), alpha, f, p);
  return {r.slope_density, r.density, r.alpha_eff};
}

// The glint material and footprint as glints.glsl's structs.
template <class T>
typename Glsl<T>::GlintMaterial GlslGlintMaterial(const MaterialDesc& material) {
  typename Glsl<T>::GlintMaterial g;
  g.alpha = glm::vec<2, T>(material.alpha);
  g.alphaL = T(material.glint_alpha_l);
  g.density = T(material.glint_density);
  return g;
}
template <class T>
typename Glsl<T>::GlintFootprint GlslGlintFootprint(const GlintFootprint<T>& footprint) {
  typename Glsl<T>::GlintFootprint f;
  f.uv = footprint.uv;
  f.duvdx = footprint.duvdx;
  f.duvdy = footprint.duvdy;
  f.areaScale = footprint.area_scale;
  f.dhppdx = footprint.dhppdx;
  f.dhppdy = footprint.dhppdy;
  return f;
}

template <class T>
FilteredNdf<T> EvaluateGlints(GlintMode mode, const MaterialDesc& material, glm::vec<2, T> hpp,
                              const GlintFootprint<T>& footprint) {
  auto r = Glsl<T>::Glint(static_cast<int>(mode), GlslGlintMaterial<T>(material), hpp, GlslGlintFootprint(footprint));
  return {r.slope_density, r.density, r.alpha_eff};
}
template <class T>
GlintCount<T> CountGlints(GlintMode mode, const MaterialDesc& material, glm::vec<2, T> hpp,
                          const GlintFootprint<T>& footprint) {
  auto r = Glsl<T>::Count(static_cast<int>(mode), GlslGlintMaterial<T>(material), hpp, GlslGlintFootprint(footprint));
  return {r.count, r.total, r.binArea};
}
template <class T>
T GlintBinomial(T n, T p, T u, T u2) {
  return Glsl<T>::Binomial(n, p, u, u2);
}
template <class T>
T GlintInterval(T lo, T hi, T alpha) {
  return Glsl<T>::Interval(lo, hi, alpha);
}

template <class T>
T SlopeDensity(Ndf ndf, glm::vec<2, T> slope, glm::vec<2, T> alpha) {
  return Glsl<T>::Density(static_cast<int>(ndf), slope, alpha);
}
template <class T>
T GgxRectMeanSeed(glm::vec<2, T> centre, glm::vec<2, T> alpha, glm::vec<2, T> half_sides) {
  return Glsl<T>::RectSeed(centre, alpha, half_sides);
}
template <class T>
T GgxRectMeanStable(glm::vec<2, T> centre, glm::vec<2, T> alpha, glm::vec<2, T> half_sides) {
  return Glsl<T>::RectStable(centre, alpha, half_sides);
}
template <class T>
T GgxRectMeanJacobian(glm::vec<2, T> centre, glm::vec<2, T> alpha, glm::vec<2, T> half_sides) {
  return Glsl<T>::RectJacobian(centre, alpha, half_sides);
}

// --- Spherical Gaussians (sg.glsl) ---------------------------------------------

namespace {
// sg.glsl's functions are found by argument-dependent lookup on the SG / ASG
// types of Glsl<T>'s namespace; the two that take no such argument are in
// Glsl<T> itself.

template <class T>
typename Glsl<T>::SG ToGlsl(const Sg<T>& g) {
  typename Glsl<T>::SG r;
  r.axis = g.axis;
  r.sharpness = g.sharpness;
  r.amplitude = g.amplitude;
  return r;
}
template <class T>
typename Glsl<T>::ASG ToGlsl(const Asg<T>& g) {
  typename Glsl<T>::ASG r;
  r.basisX = g.basis_x;
  r.basisY = g.basis_y;
  r.basisZ = g.basis_z;
  r.sharpnessX = g.sharpness_x;
  r.sharpnessY = g.sharpness_y;
  r.amplitude = g.amplitude;
  return r;
}
template <class GlslSg>
auto FromGlslSg(const GlslSg& g) {
  using T = decltype(g.sharpness);
  return Sg<T>{g.axis, g.sharpness, g.amplitude};
}
template <class GlslAsg>
auto FromGlslAsg(const GlslAsg& g) {
  using T = decltype(g.sharpnessX);
  return Asg<T>{g.basisX, g.basisY, g.basisZ, g.sharpnessX, g.sharpnessY, g.amplitude};
}
}  // namespace

template <class T>
glm::vec<3, T> SgEvaluate(const Sg<T>& sg, glm::vec<3, T> dir) {
  return sgEvaluate(ToGlsl(sg), dir);
}
template <class T>
glm::vec<3, T> SgIntegral(const Sg<T>& sg) {
  return sgIntegral(ToGlsl(sg));
}
template <class T>
glm::vec<3, T> SgInnerProduct(const Sg<T>& a, const Sg<T>& b) {
  return sgInnerProduct(ToGlsl(a), ToGlsl(b));
}
template <class T>
T OneMinusExpNegOver(T y) {
  return Glsl<T>::OneMinusExpNegOver(y);
}
template <class T>
Sg<T> DistributionTermSg(glm::vec<3, T> normal, T alpha) {
  return FromGlslSg(Glsl<T>::SgNdf(normal, alpha));
}
template <class T>
Sg<T> WarpDistributionSg(const Sg<T>& ndf, glm::vec<3, T> view) {
  return FromGlslSg(warpDistributionSG(ToGlsl(ndf), view));
}
template <class T>
Asg<T> WarpDistributionAsg(const Sg<T>& ndf, glm::vec<3, T> view) {
  return FromGlslAsg(warpDistributionASG(ToGlsl(ndf), view));
}
template <class T>
glm::vec<3, T> AsgEvaluate(const Asg<T>& asg, glm::vec<3, T> dir) {
  return asgEvaluate(ToGlsl(asg), dir);
}
template <class T>
glm::vec<3, T> ConvolveAsgSg(const Asg<T>& asg, const Sg<T>& sg) {
  return convolveASG_SG(ToGlsl(asg), ToGlsl(sg));
}
template <class T>
glm::vec<3, T> SpecularTermSgWarp(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view,
                                  glm::vec<3, T> f0) {
  return specularTermSGWarp(ToGlsl(light), normal, alpha, view, f0);
}
template <class T>
glm::vec<3, T> SpecularTermAsgWarp(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view,
                                   glm::vec<3, T> f0) {
  return specularTermASGWarp(ToGlsl(light), normal, alpha, view, f0);
}

namespace {
// A flat surface point under `light` shaded by variant none (the tests' view
// of sg_light.glsl).
template <class T>
auto FlatSgPoint(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view, glm::vec<3, T> f0) {
  typename Glsl<T>::SgShadingPoint p;
  p.light = ToGlsl(light);
  p.n = normal;
  p.t = Glsl<T>::Perpendicular(normal);
  p.b = cross(normal, p.t);
  p.ng = normal;
  p.v = glm::vec<3, T>(dot(view, p.t), dot(view, p.b), dot(view, normal));
  p.variant = 0;
  p.ndf = 0;
  p.alpha = glm::vec<2, T>(alpha);
  p.alphaEff = p.alpha;
  p.f0 = f0;
  p.f.hpp = glm::vec<2, T>(0);
  p.f.dhpp_dx = p.f.dhpp_dy = p.f.dh_dx = p.f.dh_dy = glm::vec<2, T>(0);
  p.f.n = normal;
  p.f.dn_dx = p.f.dn_dy = p.f.dng_dx = p.f.dng_dy = glm::vec<3, T>(0);
  p.vp = GlslVariantParams<typename Glsl<T>::VariantParams>(Params<T>{});  // variant 0 reads none of them
  return p;
}
}  // namespace

template <class T>
glm::vec<3, T> SgLightSpecularEstimate(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view,
                                       glm::vec<3, T> f0, glm::vec<2, T> u_light, glm::vec<2, T> u_brdf) {
  return sgSpecular(FlatSgPoint(light, normal, alpha, view, f0),
                    glm::vec<4, T>(u_light, glm::vec<2, T>(u_brdf.y, u_brdf.x)));
}
template <class T>
glm::vec<3, T> SgLightSpecularQuadrature(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view,
                                         glm::vec<3, T> f0) {
  return sgSpecular(FlatSgPoint(light, normal, alpha, view, f0), glm::vec<4, T>(-1, 0, 0, 0));
}
template <class T>
glm::vec<3, T> SgIrradiance(const Sg<T>& light, glm::vec<3, T> normal) {
  return sgIrradiance(ToGlsl(light), normal);
}
template <class T>
glm::vec<3, T> SgIrradianceEstimate(const Sg<T>& light, glm::vec<3, T> normal, glm::vec<2, T> u) {
  return sgIrradianceEstimate(ToGlsl(light), normal, u);
}
template <class T>
glm::vec<3, T> SgSampleDirection(const Sg<T>& light, glm::vec<2, T> u) {
  return sgSampleDirection(ToGlsl(light), u);
}
template <class T>
T SgDirectionPdf(const Sg<T>& light, glm::vec<3, T> dir) {
  return sgDirectionPdf(ToGlsl(light), dir);
}

#define SHIMMER_INSTANTIATE(T)                                                                                        \
  template glm::vec<3, T> SgLightSpecularEstimate<T>(const Sg<T>&, glm::vec<3, T>, T, glm::vec<3, T>, glm::vec<3, T>, \
                                                     glm::vec<2, T>, glm::vec<2, T>);                                 \
  template glm::vec<3, T> SgLightSpecularQuadrature<T>(const Sg<T>&, glm::vec<3, T>, T, glm::vec<3, T>,               \
                                                       glm::vec<3, T>);                                               \
  template glm::vec<3, T> SgIrradiance<T>(const Sg<T>&, glm::vec<3, T>);                                              \
  template glm::vec<3, T> SgIrradianceEstimate<T>(const Sg<T>&, glm::vec<3, T>, glm::vec<2, T>);                      \
  template glm::vec<3, T> SgSampleDirection<T>(const Sg<T>&, glm::vec<2, T>);                                         \
  template T SgDirectionPdf<T>(const Sg<T>&, glm::vec<3, T>);                                                         \
  template glm::vec<3, T> SgEvaluate<T>(const Sg<T>&, glm::vec<3, T>);                                                \
  template glm::vec<3, T> SgIntegral<T>(const Sg<T>&);                                                                \
  template glm::vec<3, T> SgInnerProduct<T>(const Sg<T>&, const Sg<T>&);                                              \
  template T OneMinusExpNegOver<T>(T);                                                                                \
  template Sg<T> DistributionTermSg<T>(glm::vec<3, T>, T);                                                            \
  template Sg<T> WarpDistributionSg<T>(const Sg<T>&, glm::vec<3, T>);                                                 \
  template Asg<T> WarpDistributionAsg<T>(const Sg<T>&, glm::vec<3, T>);                                               \
  template glm::vec<3, T> AsgEvaluate<T>(const Asg<T>&, glm::vec<3, T>);                                              \
  template glm::vec<3, T> ConvolveAsgSg<T>(const Asg<T>&, const Sg<T>&);                                              \
  template glm::vec<3, T> SpecularTermSgWarp<T>(const Sg<T>&, glm::vec<3, T>, T, glm::vec<3, T>, glm::vec<3, T>);     \
  template glm::vec<3, T> SpecularTermAsgWarp<T>(const Sg<T>&, glm::vec<3, T>, T, glm::vec<3, T>, glm::vec<3, T>);
SHIMMER_INSTANTIATE(float)
SHIMMER_INSTANTIATE(double)
#undef SHIMMER_INSTANTIATE

#define SHIMMER_INSTANTIATE(T)                                                                                 \
  template FilteredNdf<T> EvaluateVariant<T>(int, Ndf, glm::vec<2, T>, const Footprint<T>&, const Params<T>&); \
  template T SlopeDensity<T>(Ndf, glm::vec<2, T>, glm::vec<2, T>);                                             \
  template Footprint<T> WithChainedProjection<T>(Footprint<T>);                                                \
  template FilteredNdf<T> EvaluateGlints<T>(GlintMode, const MaterialDesc&, glm::vec<2, T>,                     \
                                            const GlintFootprint<T>&);                                          \
  template GlintCount<T> CountGlints<T>(GlintMode, const MaterialDesc&, glm::vec<2, T>, const GlintFootprint<T>&); \
  template T GlintBinomial<T>(T, T, T, T);                                                                      \
  template T GlintInterval<T>(T, T, T);                                                                         \
  template T GgxRectMeanSeed<T>(glm::vec<2, T>, glm::vec<2, T>, glm::vec<2, T>);                               \
  template T GgxRectMeanStable<T>(glm::vec<2, T>, glm::vec<2, T>, glm::vec<2, T>);                             \
  template T GgxRectMeanJacobian<T>(glm::vec<2, T>, glm::vec<2, T>, glm::vec<2, T>);
SHIMMER_INSTANTIATE(float)
SHIMMER_INSTANTIATE(double)
#undef SHIMMER_INSTANTIATE

namespace {
template <class Camera>
Camera GlslCamera(const CameraDesc& camera) {
  using V3 = decltype(Camera::pos);
  using V2 = decltype(Camera::size);
  using Real = decltype(Camera::aspect);
  Camera c;
  c.pos = V3(camera.pos);
  c.fwd = V3(camera.fwd);
  c.right = V3(camera.right);
  c.up = V3(camera.up);
  c.tanHalfFovY = Real(camera.tan_half_fov_y);
  c.aspect = Real(double(camera.width) / double(camera.height));
  c.size = V2(camera.width, camera.height);
  return c;
}
}  // namespace

PixelTraceCheck TracePixelBothWays(std::span<const glm::vec4> scene_words, int scene_features, const CameraDesc& camera,
                                   glm::ivec2 px, glm::dvec2 offset) {
  using namespace glsl_f32;
  g_scene_words = scene_words;
  g_scene_features = scene_features;
  Camera c = GlslCamera<Camera>(camera);
  Ray r = cameraRay(c, vec2(px) + vec2(offset));
  Hit full = traceScene(r.o, r.d);
  PixelCandidates l = pixelCandidates(pixelCone(c, px));
  PixelTraceCheck out;
  out.scene_prim = full.prim;
  out.scene_t = full.t;
  out.candidates = l.count;
  if (l.count <= PIXEL_CANDIDATES) {
    Hit h = traceCandidates(l, r.o, r.d);
    out.candidate_prim = h.prim;
    out.candidate_t = h.t;
  }
  g_scene_words = {};
  g_scene_features = kAllSceneFeatures;
  return out;
}

SurfaceUvFrame SurfaceUvFrameAt(std::span<const glm::vec4> scene_words, int prim, glm::dvec3 p) {
  using namespace glsl_f64;
  g_scene_words = scene_words;
  const Prim pr = loadPrim(prim);
  const GeometricFrame f = geometricFrame(pr, p);
  const UvGradient g = surfaceUvGradient(pr, p);
  SurfaceUvFrame o{surfaceUv(pr, p), f.t, f.b, f.n, g.du, g.dv, surfaceUPeriod(pr)};
  g_scene_words = {};
  return o;
}

namespace {
glsl_f64::NormalMapStats StatsOf(const NormalMapRead& r) {
  glsl_f64::NormalMapStats s;
  s.meanN = glm::dvec3(r.mean_normal_ft);
  s.ft = r.mean_normal_ft.w;
  s.b = r.b;
  s.m = r.m;
  return s;
}
}  // namespace

NormalMapRead ReadNormalMap(std::span<const glm::vec4> scene_words, int prim, int nmf, glm::dvec2 uv,
                            glm::dvec2 duv_dx, glm::dvec2 duv_dy) {
  using namespace glsl_f64;
  g_scene_words = scene_words;
  NormalMapFilter nf;
  nf.mode = nmf;
  nf.duvdx = duv_dx;
  nf.duvdy = duv_dy;
  const NormalMapStats s = normalMapStats(loadPrim(prim).map, nf, uv);
  g_scene_words = {};
  return {glm::dvec4(s.meanN, s.ft), s.b, s.m};
}

glm::dvec3 NormalMapFilterNormal(int nmf, const NormalMapRead& read) {
  return glsl_f64::normalMapNormal(nmf, StatsOf(read));
}

glm::dvec2 NormalMapFilterAlpha(int nmf, const NormalMapRead& read, glm::dvec2 alpha, double scale) {
  return glsl_f64::normalMapAlpha(nmf, StatsOf(read), alpha, scale);
}

NormalMapFilterLobe NormalMapLobe(int nmf, const NormalMapRead& read, glm::dvec2 alpha, double scale) {
  const auto l = glsl_f64::normalMapLobe(nmf, StatsOf(read), alpha, scale);
  return {l.alpha, l.angle};
}

PixelOracle ShadePixel(std::span<const glm::vec4> scene_words, const CameraDesc& camera, const LightDesc& light,
                       const MaterialDesc& material, int variant, DerivativeSource derivatives,
                       const Params<double>& params, glm::ivec2 px) {
  using namespace glsl_f64;
  g_scene_words = scene_words;
  // Every primitive kind (absent kinds cost the CPU nothing); shadows where the light casts them.
  g_scene_features = kAllSceneFeatures | (light.shadows ? kSceneShadows : 0);
  Camera c = GlslCamera<Camera>(camera);
  Light l;
  l.type = static_cast<int>(light.type);
  l.vec = light.vec;
  l.radiance = light.radiance;
  l.radius = light.radius;
  Material m;
  m.ndf = static_cast<int>(material.ndf);
  m.alpha = material.alpha;
  m.f0 = material.f0;
  m.albedo = material.albedo;
  m.glintAlphaL = material.glint_alpha_l;
  m.glintDensity = material.glint_density;
  const auto p = GlslVariantParams<VariantParams>(params);
  PixelResult r = renderPixelOracle(c, l, m, variant, static_cast<int>(derivatives), p, px);
  g_scene_words = {};
  g_scene_features = kAllSceneFeatures;
  PixelOracle o;
  o.hit = r.s.prim >= 0;
  o.prim = r.s.prim;
  o.depth = r.s.t;
  o.normal = r.s.n;
  o.hpp = r.s.hpp;
  o.specular = r.shade.specular;
  o.diffuse = r.shade.diffuse;
  o.alpha_eff = r.shade.alphaEff;
  o.footprint = r.shade.footprint;
  o.derivatives = {r.f.hpp,    r.f.dhpp_dx, r.f.dhpp_dy, r.f.n,    r.f.dn_dx,
                   r.f.dn_dy, r.f.dng_dx,  r.f.dng_dy,  r.f.dh_dx, r.f.dh_dy};
  return o;
}

}  // namespace shimmer::shading
