// What one pixel sample computes, shared by the GPU kernel
// (renderer/shaders/render.comp) and the CPU double oracle: the surface seen
// through a pixel, its shading footprint from either derivative source, and
// the shaded specular and diffuse radiance.

const int LIGHT_DIRECTIONAL = 0;
const int LIGHT_SPHERE = 1;
const int LIGHT_SG = 2;

const int DERIV_ANALYTIC = 0;     // ray differentials (Igehy 1999) carried to hpp (seed 000)
const int DERIV_QUAD_FINE = 1;    // 2x2 quad differences, per row / column (ddx_fine)
const int DERIV_QUAD_COARSE = 2;  // 2x2 quad differences of the quad's first row / column (ddx_coarse)

// Directional: vec = unit direction towards the light, radiance = irradiance
// at normal incidence. Sphere: vec = centre, radiance = intensity
// (irradiance at unit distance); a small sphere is shaded in its point limit
// (radius only keeps 1 / d^2 finite). Spherical Gaussian (seed 004), distant:
// vec = unit axis, radiance = amplitude (radiance along the axis), radius =
// sharpness lambda of amplitude exp(lambda (axis.l - 1)).
struct Light {
  int type;
  vec3 vec;
  vec3 radiance;
  real radius;
};

struct Material {
  int ndf;
  vec2 alpha;  // a glint material's: its microdetails' slopes (glints.glsl)
  vec3 f0;
  vec3 albedo;
  real glintAlphaL;   // a glint material's local lobe,
  real glintDensity;  // and its microdetails per unit area
};

GlintMaterial glintMaterial(Material m) {
  GlintMaterial g;
  g.alpha = m.alpha;
  g.alphaL = m.glintAlphaL;
  g.density = m.glintDensity;
  return g;
}

struct SurfaceSample {
  int prim;  // -1: the ray missed
  real t;    // distance from the eye
  vec3 p;
  vec3 n;   // shading normal
  vec3 ng;  // geometric normal
  vec3 tangent;
  vec3 bitangent;
  vec3 v;  // unit direction to the eye
  vec3 l;  // unit direction to the light
  vec3 irradiance;
  vec2 hpp;  // slope-space half vector h.xy / h.z in (tangent, bitangent, n) (seed 000)
  vec2 uv;   // texture coordinates of a normal-mapped primitive (scene.glsl), else 0
  real uPeriod;
};

vec3 lightDirection(Light light, vec3 p) {
  if (light.type == LIGHT_SPHERE) return safeNormalize(light.vec - p, vec3(real(0), real(1), real(0)));
  return light.vec;
}

vec3 lightIrradiance(Light light, vec3 p) {
  if (light.type != LIGHT_SPHERE) return light.radiance;
  vec3 d = light.vec - p;
  return light.radiance / max(dot(d, d), light.radius * light.radius);
}

// 0 where something lies between p and the light (a sphere light's centre)
// in direction l (lightDirection at p), else 1: a hard shadow, traced only by kernels of scenes whose light casts
// shadows (SCENE_SHADOWS). The ray leaves from p moved off the surface along
// the geometric normal, to the side the light is on, by a distance relative
// to the scene's scale, so that the surface does not shadow itself; a
// smooth-shaded low-poly mesh keeps its geometric terminator (its shading
// normal may face a light its triangle faces away from).
real lightVisibility(Light light, vec3 p, vec3 ng, vec3 l) {
  real side = dot(ng, l) >= real(0) ? real(1) : real(-1);
  vec3 o = p + ng * (side * real(1e-4) * (real(1) + length(p)));
  real reach = light.type == LIGHT_SPHERE ? length(light.vec - o) : RAY_TMAX;
  Hit h = traceScene(o, l);
  return h.prim >= 0 && h.t < reach ? real(0) : real(1);
}

real guardedZ(real z) {
  if (abs(z) < real(1e-8)) return z < real(0) ? real(-1e-8) : real(1e-8);
  return z;
}

SG lightSG(Light light) {
  SG g;
  g.axis = light.vec;
  g.sharpness = light.radius;
  g.amplitude = light.radiance;
  return g;
}

SurfaceSample missedSample() {
  SurfaceSample s;
  s.prim = -1;
  s.t = real(0);
  s.p = vec3(real(0), real(0), real(0));
  s.n = s.p;
  s.ng = s.p;
  s.tangent = s.p;
  s.bitangent = s.p;
  s.v = s.p;
  s.l = s.p;
  s.irradiance = s.p;
  s.hpp = vec2(real(0), real(0));
  s.uv = s.hpp;
  s.uPeriod = real(0);
  return s;
}

// Surface attributes of primitive `prim` at point p (p may lie off the
// surface when a neighbour's ray is continued on this primitive) with
// shading normal n.
SurfaceSample surfaceWithNormal(Prim pr, int prim, vec3 p, vec3 eye, Light light, vec3 n) {
  SurfaceSample s;
  s.prim = prim;
  s.p = p;
  s.t = length(eye - p);
  s.ng = geometricNormalAt(pr, p);
  s.n = n;
  s.uv = vec2(real(0), real(0));
  s.uPeriod = real(0);
  if (isMapped(pr)) {
    s.uv = surfaceUv(pr, p);
    s.uPeriod = surfaceUPeriod(pr);
  }
  s.tangent = normalize(cross(tangentAxis(pr, s.n), s.n));
#ifdef SHIMMER_MESHES
  if (isTriangle(pr)) s.tangent = triangleShadingTangent(pr, p, s.n);
#endif
  s.bitangent = cross(s.n, s.tangent);
  s.v = safeNormalize(eye - p, s.n);
  s.l = lightDirection(light, p);
  s.irradiance = lightIrradiance(light, p);
  if ((SCENE_FEATURES & SCENE_SHADOWS) != 0) s.irradiance = s.irradiance * lightVisibility(light, p, s.ng, s.l);
  vec3 h = safeNormalize(s.v + s.l, s.n);
  real hz = guardedZ(dot(h, s.n));
  s.hpp = vec2(dot(h, s.tangent), dot(h, s.bitangent)) / hz;
  return s;
}

// The same with the normal map read through filter nf.
SurfaceSample surfaceOfPrimFiltered(Prim pr, int prim, vec3 p, vec3 eye, Light light, NormalMapFilter nf) {
  return surfaceWithNormal(pr, prim, p, eye, light, shadingNormalFiltered(pr, p, nf));
}

SurfaceSample surfaceOfPrim(Prim pr, int prim, vec3 p, vec3 eye, Light light) {
  return surfaceOfPrimFiltered(pr, prim, p, eye, light, levelZeroFilter());
}

SurfaceSample surfaceAt(int prim, vec3 p, vec3 eye, Light light) {
  return surfaceOfPrim(loadPrim(prim), prim, p, eye, light);
}

// The material at sample s: a mesh's roughness texture scales alpha by its
// texel's (G / mean G)^2 there (scene.glsl, "Roughness textures"), read at
// level 0 as nm-point reads a normal map, so that the material's alpha is
// the texture's mean. Callers test SCENE_ROUGHNESS_MAPS first, so that the
// kernels of scenes without a roughness texture hold no trace of the call
// (their SPIR-V, hence their job ids, stay as they were).
Material materialAt(Material m, SurfaceSample s) {
#ifdef SHIMMER_MESHES
  if ((SCENE_FEATURES & SCENE_ROUGHNESS_MAPS) == 0 || s.prim < 0) return m;
  Prim pr = loadPrim(s.prim);
  if (!isTriangle(pr)) return m;
  int header = triangleRoughnessMap(pr);
  if (header == 0) return m;
  real k = roughnessFactorAt(header, triangleUv(pr, s.p));
  m.alpha = min(max(m.alpha * k, vec2(real(1e-4), real(1e-4))), vec2(real(1), real(1)));
#endif
  return m;
}

// Sample s (of any primitive) seen through normal-map filter nf; a missed
// sample stays missed.
SurfaceSample filteredSample(SurfaceSample s, vec3 eye, Light light, NormalMapFilter nf) {
  if (s.prim < 0) return s;
  return surfaceOfPrimFiltered(loadPrim(s.prim), s.prim, s.p, eye, light, nf);
}

// The pixel's own sample seen through nf, with the lobe the filter widens
// the material's alpha to there (normalMapLobe), from one read of the map.
struct FilteredCentre {
  SurfaceSample s;
  NormalMapLobe lobe;
};

FilteredCentre filteredCentre(SurfaceSample s, vec3 eye, Light light, NormalMapFilter nf, vec2 alpha, real scale) {
  FilteredCentre o;
  o.s = s;  // an unmapped primitive's sample is the same through any filter
  o.lobe.alpha = alpha;
  o.lobe.angle = real(0);
  if (s.prim < 0) return o;
  Prim pr = loadPrim(s.prim);
  if (!isMapped(pr)) return o;
  NormalMapStats st = normalMapStats(pr.map, nf, s.uv);  // surfaceWithNormal's uv of this mapped point
  o.s = surfaceWithNormal(pr, s.prim, s.p, eye, light, mappedNormal(pr, s.p, normalMapNormal(nf.mode, st)));
  o.lobe = normalMapLobe(nf.mode, st, alpha, scale);
  return o;
}

SurfaceSample surfaceOfHit(Hit hit, Ray r, Light light) {
  if (hit.prim < 0) return missedSample();
  return surfaceAt(hit.prim, r.o + r.d * hit.t, r.o, light);
}

SurfaceSample traceRay(Ray r, Light light) { return surfaceOfHit(traceScene(r.o, r.d), r, light); }

// traceRay for a ray inside the pixel whose candidates l holds.
SurfaceSample tracePixelRay(PixelCandidates l, Ray r, Light light) {
  Hit hit = traceCandidates(l, r.o, r.d);
  if (hit.prim < 0) return missedSample();
  return surfaceOfPrim(candidatePrim(l, hit.prim), hit.prim, r.o + r.d * hit.t, r.o, light);
}

// A pixel shader's helper lane keeps interpolating its own triangle past the
// silhouette; the analytic counterpart continues the neighbour pixel's ray
// onto this sample's tangent plane and evaluates this primitive there.
SurfaceSample continueOnPrim(SurfaceSample s, Camera c, Light light, vec2 pix) {
  if (s.prim < 0) return s;
  Ray r = cameraRay(c, pix);
  real denom = dot(r.d, s.ng);
  if (abs(denom) < real(1e-9)) return s;
  real t = dot(s.p - r.o, s.ng) / denom;
  if (!(t > real(0))) return s;
  return surfaceAt(s.prim, r.o + r.d * t, r.o, light);
}

// Quad finite differences: x0/x1 are the left/right samples of the row used
// for d/dx, y0/y1 the top/bottom samples of the column used for d/dy.
ShadingFootprint quadFootprint(SurfaceSample s, SurfaceSample x0, SurfaceSample x1, SurfaceSample y0,
                               SurfaceSample y1) {
  ShadingFootprint f;
  f.hpp = s.hpp;
  f.n = s.n;
  f.dhpp_dx = x1.hpp - x0.hpp;
  f.dhpp_dy = y1.hpp - y0.hpp;
  // TK19's forward kernel differences h.xy itself, not the slope.
  f.dh_dx = projectedHalfVector(x1.hpp) - projectedHalfVector(x0.hpp);
  f.dh_dy = projectedHalfVector(y1.hpp) - projectedHalfVector(y0.hpp);
  f.dn_dx = x1.n - x0.n;
  f.dn_dy = y1.n - y0.n;
  f.dng_dx = x1.ng - x0.ng;
  f.dng_dy = y1.ng - y0.ng;
  return f;
}

// A uv footprint: the change of uv per pixel along screen x and y, what a
// texture fetch takes as its footprint (the normal map's and the glints').
struct UvFootprint {
  vec2 dx;
  vec2 dy;
};

// From the quad's uv differences dx, dy; u wraps (period > 0) on spheres and
// capsules.
real wrappedDifference(real d, real period) { return period > real(0) ? d - period * floor(d / period + real(0.5)) : d; }
UvFootprint quadUvFootprint(vec2 dx, vec2 dy, real period) {
  UvFootprint f;
  f.dx = vec2(wrappedDifference(dx.x, period), dx.y);
  f.dy = vec2(wrappedDifference(dy.x, period), dy.y);
  return f;
}

NormalMapFilter quadNormalMapFilter(int mode, SurfaceSample s, SurfaceSample x0, SurfaceSample x1, SurfaceSample y0,
                                    SurfaceSample y1) {
  NormalMapFilter nf;
  nf.mode = mode;
  UvFootprint uv = quadUvFootprint(x1.uv - x0.uv, y1.uv - y0.uv, s.uPeriod);
  nf.duvdx = uv.dx;
  nf.duvdy = uv.dy;
  return nf;
}

ShadingFootprint zeroFootprint(SurfaceSample s) {
  ShadingFootprint f;
  vec3 z = vec3(real(0), real(0), real(0));
  f.hpp = s.hpp;
  f.n = s.n;
  f.dhpp_dx = vec2(real(0), real(0));
  f.dhpp_dy = f.dhpp_dx;
  f.dh_dx = f.dhpp_dx;
  f.dh_dy = f.dhpp_dx;
  f.dn_dx = z;
  f.dn_dy = z;
  f.dng_dx = z;
  f.dng_dy = z;
  return f;
}

// d hpp for a move dp on the surface with shading-normal change dn: the
// change of the view and light directions and of the whole tangent frame
// (curvature), chained by hand through h = normalize(v + l) and
// hpp = (h.t, h.b) / h.n (seed 000, "Filtering Shading Normals" and ray differentials).
vec2 hppDerivative(SurfaceSample s, Prim pr, Light light, vec3 dp, vec3 dn) {
  vec3 dv = dNormalize(s.v * s.t, -dp);
  vec3 dl = vec3(real(0), real(0), real(0));
  if (light.type == LIGHT_SPHERE) dl = dNormalize(light.vec - s.p, -dp);
  vec3 hv = s.v + s.l;
  vec3 h = safeNormalize(hv, s.n);
  vec3 dh = dNormalize(hv, dv + dl);
  vec3 axis = tangentAxis(pr, s.n);
  vec3 dt = dNormalize(cross(axis, s.n), cross(axis, dn));
#ifdef SHIMMER_MESHES
  if (isTriangle(pr)) dt = triangleShadingTangentDeriv(pr, s.p, s.n, dp, dn);
#endif
  vec3 db = cross(dn, s.tangent) + cross(s.n, dt);
  vec3 hl = vec3(dot(h, s.tangent), dot(h, s.bitangent), guardedZ(dot(h, s.n)));
  vec3 dhl = vec3(dot(dh, s.tangent) + dot(h, dt), dot(dh, s.bitangent) + dot(h, db), dot(dh, s.n) + dot(h, dn));
  return (vec2(dhl.x, dhl.y) * hl.z - vec2(hl.x, hl.y) * dhl.z) / (hl.z * hl.z);
}

// Ray differentials transferred to the hit point (Igehy 1999, origin fixed):
// dp = t dd - d (t dd . ng) / (d . ng).
vec3 surfaceDifferential(SurfaceSample s, Ray r, vec3 dd) {
  real dn = guardedZ(dot(r.d, s.ng));
  vec3 dp = dd * s.t;
  return dp - r.d * (dot(dp, s.ng) / dn);
}

// The uv footprint from the ray differentials: d uv = (grad u . dp, grad v . dp).
UvFootprint analyticUvFootprint(SurfaceSample s, Ray r, Prim pr) {
  UvGradient g = surfaceUvGradient(pr, s.p);
  vec3 dpx = surfaceDifferential(s, r, r.ddx);
  vec3 dpy = surfaceDifferential(s, r, r.ddy);
  UvFootprint f;
  f.dx = vec2(dot(g.du, dpx), dot(g.dv, dpx));
  f.dy = vec2(dot(g.du, dpy), dot(g.dv, dpy));
  return f;
}

NormalMapFilter analyticNormalMapFilter(int mode, SurfaceSample s, Ray r) {
  NormalMapFilter nf = levelZeroFilter();
  nf.mode = mode;
  if (s.prim < 0) return nf;
  UvFootprint uv = analyticUvFootprint(s, r, loadPrim(s.prim));
  nf.duvdx = uv.dx;
  nf.duvdy = uv.dy;
  return nf;
}

// dp from the ray differentials, then through the surface to n and hpp; the
// shading normal's change as filter nf reads the normal map.
ShadingFootprint analyticFootprintFiltered(SurfaceSample s, Ray r, Light light, NormalMapFilter nf) {
  if (s.prim < 0) return zeroFootprint(s);
  Prim pr = loadPrim(s.prim);
  vec3 dpx = surfaceDifferential(s, r, r.ddx);
  vec3 dpy = surfaceDifferential(s, r, r.ddy);
  ShadingFootprint f;
  f.hpp = s.hpp;
  f.n = s.n;
  f.dn_dx = shadingNormalDerivFiltered(pr, s.p, dpx, nf);
  f.dn_dy = shadingNormalDerivFiltered(pr, s.p, dpy, nf);
  f.dng_dx = geometricNormalDeriv(pr, s.p, dpx);
  f.dng_dy = geometricNormalDeriv(pr, s.p, dpy);
  f.dhpp_dx = hppDerivative(s, pr, light, dpx, f.dn_dx);
  f.dhpp_dy = hppDerivative(s, pr, light, dpy, f.dn_dy);
  f.dh_dx = projectedHalfVectorChange(s.hpp, f.dhpp_dx);
  f.dh_dy = projectedHalfVectorChange(s.hpp, f.dhpp_dy);
  return f;
}

ShadingFootprint analyticFootprint(SurfaceSample s, Ray r, Light light) {
  return analyticFootprintFiltered(s, r, light, levelZeroFilter());
}

// ---- glint footprints (glints.glsl) ------------------------------------------
// Glints live in scene.glsl's uv stretched to lengths on the surface, so that
// a material's density (per unit area) means the same on every primitive:
// planes as they are; spheres u times the equator's circumference and v
// times half of it; capsules u times the circumference.
vec2 glintUvScale(Prim p) {
  if (isSphere(p)) return vec2(real(2) * PI * p.radius, PI * p.radius);
  if (isCapsule(p)) return vec2(real(2) * PI * p.radius, real(1));
  return vec2(real(1), real(1));
}

// Surface area per unit of that uv area: rho / r on a sphere, whose u lines
// shorten towards the poles; 1 elsewhere.
real glintAreaScale(Prim p, vec3 q) {
  if (!isSphere(p)) return real(1);
  vec3 d = q - p.a;
  return max(length(vec2(d.x, d.z)) / p.radius, real(1e-6));
}

GlintFootprint pointGlintFootprint(SurfaceSample s) {
  GlintFootprint g;
  g.uv = vec2(real(0), real(0));
  g.duvdx = g.uv;
  g.duvdy = g.uv;
  g.areaScale = real(1);
  g.dhppdx = g.uv;
  g.dhppdy = g.uv;
  if (s.prim < 0) return g;
  Prim pr = loadPrim(s.prim);
  g.uv = surfaceUv(pr, s.p) * glintUvScale(pr);
  g.areaScale = glintAreaScale(pr, s.p);
  return g;
}

// From the quad's neighbours (x0/x1 along x, y0/y1 along y, as quadFootprint).
GlintFootprint quadGlintFootprint(SurfaceSample s, SurfaceSample x0, SurfaceSample x1, SurfaceSample y0,
                                  SurfaceSample y1) {
  GlintFootprint g = pointGlintFootprint(s);
  if (s.prim < 0) return g;
  Prim pr = loadPrim(s.prim);
  vec2 scale = glintUvScale(pr);
  real period = surfaceUPeriod(pr) * scale.x;
  // The neighbours' points in the centre primitive's uv (they may lie on another primitive).
  UvFootprint uv = quadUvFootprint((surfaceUv(pr, x1.p) - surfaceUv(pr, x0.p)) * scale,
                                   (surfaceUv(pr, y1.p) - surfaceUv(pr, y0.p)) * scale, period);
  g.duvdx = uv.dx;
  g.duvdy = uv.dy;
  return g;
}

// From the ray differentials: d uv = (grad u . dp, grad v . dp).
GlintFootprint analyticGlintFootprint(SurfaceSample s, Ray r) {
  GlintFootprint g = pointGlintFootprint(s);
  if (s.prim < 0) return g;
  Prim pr = loadPrim(s.prim);
  vec2 scale = glintUvScale(pr);
  UvFootprint uv = analyticUvFootprint(s, r, pr);
  g.duvdx = uv.dx * scale;
  g.duvdy = uv.dy * scale;
  return g;
}

// A glint material's NDF as the variant shades it (none: the finest level
// at the point).
FilteredNdf glintNdfOf(int variant, Material m, SurfaceSample s, GlintFootprint g) {
  return glintNdf(glintModeOf(variant), glintMaterial(m), s.hpp, g);
}

struct PixelShade {
  vec3 specular;
  vec3 diffuse;
  vec2 alphaEff;
  vec2 footprint;  // slope-space footprint half-sides (|dx hpp| + |dy hpp|) / 2
};

// An SG light's specular: seed 004's closed forms for the SG variants, else
// the exact BRDF with the variant's filtered D at every direction of the
// light integral, by Monte Carlo with the sample's random numbers u (one 2D
// point per strategy, the reference) when u.x >= 0, else by the fixed
// quadrature (sg_light.glsl). Diffuse: the irradiance on the shading normal,
// estimated from the light sample (reference) or converged.
PixelShade shadeUnderSg(PixelShade o, SurfaceSample s, ShadingFootprint f, FilteredNdf ndf, Material m, Light light,
                        int variant, VariantParams vp, vec4 u) {
  SG g = lightSG(light);
  if (u.x >= real(0))
    o.diffuse = m.albedo * sgIrradianceEstimate(g, s.n, vec2(u.x, u.y)) / PI;
  else
    o.diffuse = m.albedo * sgIrradiance(g, s.n) / PI;
  if (isSgVariant(variant)) {
    real a = sqrt(ndf.alpha_eff.x * ndf.alpha_eff.y);  // one isotropic SG lobe: the geometric mean
    if (variant == VARIANT_SG_WARP || variant == VARIANT_SG_WARP_K16)
      o.specular = specularTermSGWarp(g, s.n, a, s.v, m.f0);
    else
      o.specular = specularTermASGWarp(g, s.n, a, s.v, m.f0);
    return o;
  }
  SgShadingPoint p;
  p.light = g;
  p.t = s.tangent;
  p.b = s.bitangent;
  p.n = s.n;
  p.ng = s.ng;
  p.v = vec3(dot(s.v, s.tangent), dot(s.v, s.bitangent), dot(s.v, s.n));
  p.variant = variant;
  p.ndf = m.ndf;
  p.alpha = m.alpha;
  p.alphaEff = ndf.alpha_eff;
  p.f0 = m.f0;
  p.f = f;
  p.vp = vp;
  o.specular = sgSpecular(p, u);
  return o;
}

PixelShade shadeSample(SurfaceSample s, ShadingFootprint f, FilteredNdf ndf, Material m, Light light, int variant,
                       VariantParams vp, vec4 u) {
  PixelShade o;
  vec3 z = vec3(real(0), real(0), real(0));
  o.specular = z;
  o.diffuse = z;
  o.alphaEff = vec2(real(0), real(0));
  o.footprint = o.alphaEff;
  if (s.prim < 0) return o;
  o.alphaEff = ndf.alpha_eff;
  o.footprint = footprintHalfSides(f);
#ifndef SHIMMER_DELTA_LIGHTS_ONLY
  // A kernel for a delta-lit scene is compiled without this call (render.comp):
  // lavapipe's pipeline creation otherwise takes seconds over the SG
  // integral's inlined loops before it folds the branch away.
  if (light.type == LIGHT_SG) return shadeUnderSg(o, s, f, ndf, m, light, variant, vp, u);
#endif
  if (!(dot(s.ng, s.l) > real(0))) return o;  // light below the geometric horizon
  vec3 vl = vec3(dot(s.v, s.tangent), dot(s.v, s.bitangent), dot(s.v, s.n));
  vec3 ll = vec3(dot(s.l, s.tangent), dot(s.l, s.bitangent), dot(s.l, s.n));
  vec3 h = safeNormalize(s.v + s.l, s.n);
  o.specular = specularRadiance(m.ndf, ndf.density, ndf.alpha_eff, m.f0, vl, ll, dot(s.v, h), s.irradiance);
  o.diffuse = diffuseRadiance(m.albedo, ll.z, s.irradiance);
  return o;
}

// A slope-space vector of the tangent frame in the frame turned by `angle`.
vec2 turnedSlope(vec2 v, real c, real s) { return vec2(c * v.x + s * v.y, c * v.y - s * v.x); }

// Sample s and its footprint in the tangent frame turned to a lobe's axes
// (LEAN's): tangent and bitangent rotate about the normal, and hpp with its
// derivatives rotate with them.
SurfaceSample turnedSample(SurfaceSample s, real angle) {
  if (angle == real(0) || s.prim < 0) return s;
  real c = cos(angle);
  real sn = sin(angle);
  vec3 t = s.tangent * c + s.bitangent * sn;
  s.bitangent = s.bitangent * c - s.tangent * sn;
  s.tangent = t;
  s.hpp = turnedSlope(s.hpp, c, sn);
  return s;
}

ShadingFootprint turnedFootprint(ShadingFootprint f, real angle) {
  if (angle == real(0)) return f;
  real c = cos(angle);
  real sn = sin(angle);
  f.hpp = turnedSlope(f.hpp, c, sn);
  f.dhpp_dx = turnedSlope(f.dhpp_dx, c, sn);
  f.dhpp_dy = turnedSlope(f.dhpp_dy, c, sn);
  f.dh_dx = turnedSlope(f.dh_dx, c, sn);
  f.dh_dy = turnedSlope(f.dh_dy, c, sn);
  return f;
}

vec2 pixelCentre(ivec2 px) { return vec2(real(px.x) + real(0.5), real(px.y) + real(0.5)); }

// The sample of the neighbour pixel px as the quad sees it from s: its own
// surface when it shows the same primitive, else s's primitive continued.
SurfaceSample quadNeighbour(SurfaceSample s, SurfaceSample other, Camera c, Light light, ivec2 px) {
  if (other.prim == s.prim || s.prim < 0) return other;
  return continueOnPrim(s, c, light, pixelCentre(px));
}

// The CPU oracle of one pixel (centre sample): the kernel's computation with
// the quad's neighbours traced here instead of exchanged between invocations.
struct PixelResult {
  SurfaceSample s;
  ShadingFootprint f;
  FilteredNdf ndf;
  PixelShade shade;
};

PixelResult renderPixelOracle(Camera c, Light light, Material m, int variant, int derivMode, VariantParams vp,
                              ivec2 px) {
  PixelResult r;
  int nmf = normalMapFilterOf(variant);
  NormalMapFilter nf = levelZeroFilter();
  FilteredCentre fc;
  Ray ray = cameraRay(c, pixelCentre(px));
  r.s = traceRay(ray, light);
  if ((SCENE_FEATURES & SCENE_ROUGHNESS_MAPS) != 0) m = materialAt(m, r.s);
  GlintFootprint gf;  // set below for glint materials only
  if (r.s.prim < 0 || derivMode == DERIV_ANALYTIC) {
    if (nmf != NMF_NONE) {
      nf = analyticNormalMapFilter(nmf, r.s, ray);
      fc = filteredCentre(r.s, c.pos, light, nf, m.alpha, vp.nm_scale);
      r.s = fc.s;
    }
    r.f = analyticFootprintFiltered(r.s, ray, light, nf);
    if (m.ndf == NDF_GLINTS) gf = analyticGlintFootprint(r.s, ray);
  } else {
    ivec2 q = ivec2((px.x / 2) * 2, (px.y / 2) * 2);
    int ox = px.x - q.x;
    int oy = px.y - q.y;
    if (derivMode == DERIV_QUAD_COARSE) {
      ox = 0;
      oy = 0;
    }
    ivec2 px0 = ivec2(q.x, q.y + oy);
    ivec2 px1 = ivec2(q.x + 1, q.y + oy);
    ivec2 py0 = ivec2(q.x + ox, q.y);
    ivec2 py1 = ivec2(q.x + ox, q.y + 1);
    SurfaceSample x0 = quadNeighbour(r.s, traceRay(cameraRay(c, pixelCentre(px0)), light), c, light, px0);
    SurfaceSample x1 = quadNeighbour(r.s, traceRay(cameraRay(c, pixelCentre(px1)), light), c, light, px1);
    SurfaceSample y0 = quadNeighbour(r.s, traceRay(cameraRay(c, pixelCentre(py0)), light), c, light, py0);
    SurfaceSample y1 = quadNeighbour(r.s, traceRay(cameraRay(c, pixelCentre(py1)), light), c, light, py1);
    if (nmf != NMF_NONE) {
      // The texture fetch takes its footprint from the quad's uv; the
      // normal's differences are then those of the filtered normals.
      nf = quadNormalMapFilter(nmf, r.s, x0, x1, y0, y1);
      fc = filteredCentre(r.s, c.pos, light, nf, m.alpha, vp.nm_scale);
      r.s = fc.s;
      x0 = filteredSample(x0, c.pos, light, nf);
      x1 = filteredSample(x1, c.pos, light, nf);
      y0 = filteredSample(y0, c.pos, light, nf);
      y1 = filteredSample(y1, c.pos, light, nf);
    }
    r.f = quadFootprint(r.s, x0, x1, y0, y1);
    if (m.ndf == NDF_GLINTS) gf = quadGlintFootprint(r.s, x0, x1, y0, y1);
  }
  if (nmf != NMF_NONE) {
    m.alpha = fc.lobe.alpha;
    r.s = turnedSample(r.s, fc.lobe.angle);
    r.f = turnedFootprint(r.f, fc.lobe.angle);
  }
  if (m.ndf == NDF_GLINTS) {
    gf.dhppdx = r.f.dhpp_dx;
    gf.dhppdy = r.f.dhpp_dy;
    r.ndf = glintNdfOf(variant, m, r.s, gf);
  } else {
    r.ndf = evalVariant(variant, m.ndf, m.alpha, r.f, vp);
  }
  r.shade = shadeSample(r.s, r.f, r.ndf, m, light, variant, vp, vec4(real(-1), real(0), real(0), real(0)));
  return r;
}
