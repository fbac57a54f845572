// Spherical Gaussians (SG) and anisotropic spherical Gaussians (ASG), and the
// specular response of the GGX BRDF to an SG light as
// seeds/004_ad807e344d5111d8.txt (Pettineo, "SG Series Part 4") computes it.
// Directions are unit vectors in any one frame (world or tangent).
//
// Where the seed approximates, and by how much (numbers measured by
// tests/shading/sg_test.cpp, tabulated in docs/renderer.md):
//   - the NDF as one SG is a normalised Gaussian in the angle, not GGX: same
//     peak 1 / (pi a^2), no long tail; its projected integral
//     int D (n.h) dw is 1 - a^2/2 (1 - e^(-2/a^2)), not 1;
//   - the warps move the lobe from the half-vector to the light domain with
//     the Jacobian at the lobe centre only (SG: isotropic, ASG: stretched);
//   - the ASG x SG convolution is the planar (tangent-plane) Gaussian
//     convolution of Xu et al. 2013, exact only for sharp lobes;
//   - G, F and the cosine are taken at the warped lobe's centre, out of the
//     integral, and the NDF x light product is integrated over the whole
//     sphere (also below the horizon).

struct SG {
  vec3 axis;
  real sharpness;  // lambda of a exp(lambda (axis.d - 1))
  vec3 amplitude;
};

// a S(d, z) exp(-sharpnessX (d.x)^2 - sharpnessY (d.y)^2), S(d, z) = max(d.z, 0)
// (Xu et al. 2013, as the seed writes it).
struct ASG {
  vec3 basisX;
  vec3 basisY;
  vec3 basisZ;
  real sharpnessX;
  real sharpnessY;
  vec3 amplitude;
};

// -expm1(-y) / y = (1 - e^-y) / y for y >= 0, and 1 at y = 0. 1 - exp(-y)
// loses all digits for small y (float: y = 1e-3 keeps four), GLSL has no
// expm1, and the GPU's exp and log carry absolute errors near 1 that rule out
// Kahan's log trick, so small y takes the series (truncation below 3e-18 for
// y < 0.1; beyond it 1 - e^-y loses under four bits).
real oneMinusExpNegOver(real y) {
  if (y < real(0.1)) {
    real s = real(1) / real(3628800);  // 10!
    s = real(1) / real(362880) - y * s;
    s = real(1) / real(40320) - y * s;
    s = real(1) / real(5040) - y * s;
    s = real(1) / real(720) - y * s;
    s = real(1) / real(120) - y * s;
    s = real(1) / real(24) - y * s;
    s = real(1) / real(6) - y * s;
    s = real(1) / real(2) - y * s;
    return real(1) - y * s;
  }
  return (real(1) - exp(-y)) / y;
}

vec3 sgEvaluate(SG g, vec3 dir) { return g.amplitude * exp(max(g.sharpness, real(0)) * (dot(g.axis, dir) - real(1))); }

// int over the sphere = 2 pi a (1 - e^(-2 lambda)) / lambda (seed 004's
// series, part 2), written so that lambda -> 0 gives 4 pi a.
vec3 sgIntegral(SG g) {
  real lambda = max(g.sharpness, real(0));
  return g.amplitude * (real(4) * PI * oneMinusExpNegOver(real(2) * lambda));
}

// int over the sphere of the product of two SGs, exactly: the product is an
// SG of sharpness lm = |l1 u1 + l2 u2| times e^(lm - l1 - l2) (seed 004's
// SGInnerProduct). The seed forms lm - l1 - l2 as a difference of large
// numbers: at lambda 1e4 in float that exponent is off by ~1e-3 absolute and
// e^(...) by as much relative; and (1 - e^(-2 lm)) / lm is 0 / 0 for equal
// sharpnesses on opposite axes. Here lm - l1 - l2 = -l1 l2 |u1 - u2|^2 /
// (lm + l1 + l2) (unit axes), which is <= 0, cancels nothing and cannot
// overflow, and (1 - e^(-2 lm)) / lm has its own series.
vec3 sgInnerProduct(SG a, SG b) {
  real l1 = max(a.sharpness, real(0));
  real l2 = max(b.sharpness, real(0));
  // |l1 u1 + l2 u2| with weights <= 1 inside the length: its square would
  // overflow float for sharpnesses beyond ~1e19.
  real total = l1 + l2;
  real lm = total > real(0) ? total * length((l1 / total) * a.axis + (l2 / total) * b.axis) : real(0);
  vec3 d = a.axis - b.axis;
  real sum = lm + total;
  // Both lobes constant: the product is their amplitudes over 4 pi.
  real exponent = sum > real(0) ? -l1 * (l2 / sum) * dot(d, d) : real(0);
  return a.amplitude * b.amplitude * (real(4) * PI * exp(exponent) * oneMinusExpNegOver(real(2) * lm));
}

// The GGX NDF as one SG about the normal (seed 004, DistributionTermSG, after
// Wang et al. 2009): sharpness 2 / a^2, amplitude 1 / (pi a^2), the inverse of
// the sphere integral 2 pi / sharpness (up to e^(-4 / a^2)). Near the normal
// exp(2 (cos t - 1) / a^2) ~ exp(-t^2 / a^2): Beckmann's shape for small a.
SG distributionTermSG(vec3 normal, real alpha) {
  real a = clamp(alpha, ALPHA_MIN, ALPHA_MAX);
  real a2 = a * a;
  SG g;
  g.axis = normal;
  g.sharpness = real(2) / a2;
  g.amplitude = vec3(real(1), real(1), real(1)) / (PI * a2);
  return g;
}

vec3 reflectAbout(vec3 v, vec3 n) { return real(2) * dot(n, v) * n - v; }

// The SG warp of Wang et al. 2009 (seed 004, WarpDistributionSG): the axis is
// the view reflected about the NDF axis; the sharpness is divided by
// 4 |o.h|, the half-vector Jacobian dw_h / dw_l = 1 / (4 o.h) at the lobe
// centre, clamped at 1e-4 as the seed does (that also keeps n.v <= 0 finite).
SG warpDistributionSG(SG ndf, vec3 view) {
  SG w;
  w.axis = reflectAbout(view, ndf.axis);
  w.sharpness = ndf.sharpness / (real(4) * max(dot(ndf.axis, view), real(1e-4)));
  w.amplitude = ndf.amplitude;
  return w;
}

// Any unit vector perpendicular to unit n (Duff et al. 2017's branchless frame).
vec3 perpendicularTo(vec3 n) {
  real s = n.z >= real(0) ? real(1) : real(-1);
  real a = real(-1) / (s + n.z);
  return vec3(real(1) + s * n.x * n.x * a, s * n.x * n.y * a, -s * n.x);
}

// The ASG warp of Xu et al. 2013 (seed 004, WarpDistributionASG). The NDF SG
// exp(-lambda t^2 / 2) near its axis; a half-vector step t perpendicular to
// the plane of incidence moves the light by 2 (o.h) t, one in the plane by
// 2 t, so the light-domain lobe is exp(-lambda / (8 (o.h)^2) x^2 - lambda / 8 y^2)
// with x across and y along the plane: the highlight stretched towards the
// horizon at grazing view.
ASG warpDistributionASG(SG ndf, vec3 view) {
  ASG w;
  w.basisZ = reflectAbout(view, ndf.axis);
  // At normal view the plane of incidence is undefined (the seed's
  // normalize(cross(...)) is NaN there); the lobe is isotropic then, so any
  // perpendicular will do.
  w.basisX = safeNormalize(cross(ndf.axis, w.basisZ), perpendicularTo(w.basisZ));
  w.basisY = normalize(cross(w.basisZ, w.basisX));
  real ndotv = max(dot(view, ndf.axis), real(1e-4));
  w.sharpnessX = ndf.sharpness / (real(8) * ndotv * ndotv);
  w.sharpnessY = ndf.sharpness / real(8);
  w.amplitude = ndf.amplitude;
  return w;
}

vec3 asgEvaluate(ASG g, vec3 dir) {
  real s = sat(dot(g.basisZ, dir));
  real x = dot(dir, g.basisX);
  real y = dot(dir, g.basisY);
  return g.amplitude * (s * exp(-g.sharpnessX * x * x - g.sharpnessY * y * y));
}

// int ASG(d) SG(d) dw, as Xu et al. 2013 approximate it (seed 004,
// ConvolveASG_SG): both lobes as Gaussians on the tangent plane, whose
// convolution is the ASG with sharpnesses nu l / (nu + l) and amplitude
// pi / sqrt((nu + lx)(nu + ly)), evaluated at the SG's axis; nu = lambda / 2
// because Xu et al. write the SG as exp(2 nu (axis.d - 1)). Products are
// formed as ratios so that float does not overflow for sharp lobes.
vec3 convolveASG_SG(ASG g, SG s) {
  real nu = max(s.sharpness, real(0)) * real(0.5);
  real sumX = max(nu + g.sharpnessX, real(1e-20));
  real sumY = max(nu + g.sharpnessY, real(1e-20));
  ASG c;
  c.basisX = g.basisX;
  c.basisY = g.basisY;
  c.basisZ = g.basisZ;
  c.sharpnessX = nu * (g.sharpnessX / sumX);
  c.sharpnessY = nu * (g.sharpnessY / sumY);
  c.amplitude = vec3(real(1), real(1), real(1)) * (PI / (sqrt(sumX) * sqrt(sumY)));
  return asgEvaluate(c, s.axis) * s.amplitude * g.amplitude;
}

// The height-correlated Smith G2 of brdf.glsl (smithG2 with ggxLambda,
// isotropic) divided by 4 n.v: the visibility G2 / (4 n.l n.v) times the n.l
// of the rendering equation. 4 n.v (1 + Lambda(v)) is written as
// 2 n.v + 2 sqrt(n.v^2 + a^2 (1 - n.v^2)), so that n.v -> 0 gives 1 / (2 a)
// instead of 0 / 0. The seed uses the separable G1(l) G1(v) (its GGX_V1 is
// G1 / (2 n.x)); the height-correlated 1 / (1 + L(v) + L(l)) is never smaller
// than 1 / ((1 + L(v)) (1 + L(l))), most different where both Lambdas are
// large: rough, and grazing (Heitz 2014; sg_test.cpp prints the ratio).
real sgVisibilityTimesCos(real ndotl, real ndotv, real alpha) {
  real a = clamp(alpha, ALPHA_MIN, ALPHA_MAX);
  real nv = sat(ndotv);
  real lambdaL = ggxLambda(vec3(safeSqrt(real(1) - ndotl * ndotl), real(0), ndotl), vec2(a, a));
  real viewTerm = real(2) * nv + real(2) * sqrt(nv * nv + a * a * (real(1) - nv * nv));
  return real(1) / (viewTerm + real(4) * nv * lambdaL);
}

// G, F and the cosine at the warped lobe's centre `warpDir` (seed 004): F is
// Schlick's at the half vector between the view and the lobe centre. Below the
// horizon the seed's saturate(n.l) makes the result 0.
vec3 sgLobeCentreTerms(vec3 warpDir, vec3 normal, real alpha, vec3 view, vec3 f0) {
  real ndotl = dot(normal, warpDir);
  if (!(ndotl > real(0))) return vec3(real(0), real(0), real(0));
  // warpDir = -view at n.v = 0: h then falls back to the normal.
  vec3 h = safeNormalize(warpDir + view, normal);
  return schlickFresnel(f0, sat(dot(warpDir, h))) * sgVisibilityTimesCos(ndotl, dot(normal, view), alpha);
}

// Outgoing specular radiance towards `view` from a surface with GGX roughness
// `alpha` (the seed's `roughness`, its m; m2 = alpha^2) lit by `light`:
// L_o = int f_GGX(l, v) L(l) (n.l)+ dl, approximated as in seed 004's
// SpecularTermSGWarp: warped SG NDF x light SG inner product, times G2 F / (4 n.v)
// at the lobe centre.
vec3 specularTermSGWarp(SG light, vec3 normal, real alpha, vec3 view, vec3 f0) {
  SG ndf = distributionTermSG(normal, alpha);
  SG warped = warpDistributionSG(ndf, view);
  vec3 result = sgInnerProduct(warped, light) * sgLobeCentreTerms(warped.axis, normal, alpha, view, f0);
  return max(result, vec3(real(0), real(0), real(0)));
}

// The same with the ASG warp and the ASG x SG convolution (seed 004's
// SpecularTermASGWarp).
vec3 specularTermASGWarp(SG light, vec3 normal, real alpha, vec3 view, vec3 f0) {
  SG ndf = distributionTermSG(normal, alpha);
  ASG warped = warpDistributionASG(ndf, view);
  vec3 result = convolveASG_SG(warped, light) * sgLobeCentreTerms(warped.basisZ, normal, alpha, view, f0);
  return max(result, vec3(real(0), real(0), real(0)));
}
