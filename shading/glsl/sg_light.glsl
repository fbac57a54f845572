// Lighting from a spherical-Gaussian light L(l) = a exp(lambda (axis.l - 1))
// with the renderer's own BRDF (brdf.glsl: the material's D as the variant
// filters it, height-correlated Smith G2, Schlick F) and a Lambertian
// diffuse term: the ground truth that seed 004's SG and ASG approximations
// (sg.glsl; seeds/004_ad807e344d5111d8.txt) are measured against.
//
// Specular: L_o = int D(h) G2(v, l) F(v.h) / (4 n.v) L(l) dl over the
// directions above both the shading and the geometric horizon, estimated with
// two strategies combined by the balance heuristic (Veach 1997): directions
// drawn from the SG itself (its inverse CDF in cos theta is analytic) and
// GGX visible normals reflected about (Heitz 2018). The reference takes one
// direction of each per pixel sample, at random (Monte Carlo). Everything
// else takes both from a fixed rank-1 lattice of SG_QUADRATURE_POINTS points
// per strategy, a deterministic quadrature: a 1-spp pixel is then a smooth
// function of the view and the surface and does not flicker by itself, so
// that `none` under an SG light is the exact BRDF at the pixel centre and its
// error is aliasing, not noise.
//
// Diffuse: the irradiance int L(l) (n.l)+ dl is one-dimensional about the
// SG's axis (the azimuthal integral of (n.l)+ has a closed form) and is
// integrated with Gauss-Legendre between its kinks: converged (within 1e-4,
// sg_test.cpp checks it against a sphere quadrature), not approximated. The
// reference estimates it from its light sample instead (unbiased, and 1000
// samples of the rule per pixel would cost more than the specular).

// A Fibonacci number: the lattice below is then the Fibonacci lattice, the
// best rank-1 lattice of its size in 2D.
const int SG_QUADRATURE_POINTS = 55;
// Kernels define it as [[dont_unroll]]: unrolled, the quadrature's loop makes
// lavapipe's pipeline creation take seconds (C++ leaves it empty).
#ifndef SHIMMER_DONT_UNROLL
#define SHIMMER_DONT_UNROLL
#endif
const int SG_QUADRATURE_GENERATOR = 34;  // the Fibonacci number before it

// The kernel's variant at another half vector of the same footprint. Defined
// after the core by render.comp (the built-in or the user's variant) and by
// the C++ oracle.
FilteredNdf variantAt(int variant, int ndf, vec2 alpha, ShadingFootprint f, VariantParams p);

// 1 - e^(-2 lambda), the SG's mass over 2 pi / lambda, for lambda >= 0.
real sgMass(real lambda) { return real(2) * lambda * oneMinusExpNegOver(real(2) * lambda); }

// 1 - cos theta of the SG's inverse CDF at u in [0, 1): u = 0 is the axis.
// 1 - cos = -log(1 - u (1 - e^(-2 lambda))) / lambda, with log(1 - x) by
// its series where 1 - x would round the digits away.
real sgOneMinusCos(real lambda, real u) {
  if (lambda < real(1e-6)) return real(2) * u;  // constant lobe: uniform on the sphere
  real x = u * sgMass(lambda);
  real minusLog = x < real(1e-3) ? x * (real(1) + x * (real(0.5) + x * (real(1) / real(3) + x * real(0.25))))
                                 : -log(max(real(1) - x, real(1e-30)));
  return min(minusLog / lambda, real(2));
}

// Unit direction of the SG's distribution for u in [0, 1)^2.
vec3 sgSampleDirection(SG g, vec2 u) {
  real omc = sgOneMinusCos(max(g.sharpness, real(0)), u.x);
  real c = real(1) - omc;
  real s = safeSqrt(omc * (real(2) - omc));
  real phi = real(2) * PI * u.y;
  vec3 t = perpendicularTo(g.axis);
  vec3 b = cross(g.axis, t);
  return normalize(t * (s * cos(phi)) + b * (s * sin(phi)) + g.axis * c);
}

// Density in solid angle of sgSampleDirection: lambda e^(lambda (c - 1)) / (2 pi (1 - e^(-2 lambda))).
real sgDirectionPdf(SG g, vec3 dir) {
  real lambda = max(g.sharpness, real(0));
  real e = exp(lambda * (min(dot(g.axis, dir), real(1)) - real(1)));
  return e / (real(4) * PI * oneMinusExpNegOver(real(2) * lambda));
}

// A GGX visible normal for the local view v (v.z > 0), u in [0, 1)^2
// (Heitz 2018, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4)).
vec3 sampleGgxVisibleNormal(vec3 v, vec2 alpha, vec2 u) {
  vec3 vh = normalize(vec3(alpha.x * v.x, alpha.y * v.y, v.z));
  real lensq = vh.x * vh.x + vh.y * vh.y;
  vec3 t1 = lensq > real(1e-14) ? vec3(-vh.y, vh.x, real(0)) * inversesqrt(lensq) : vec3(real(1), real(0), real(0));
  vec3 t2 = cross(vh, t1);
  real r = sqrt(u.x);
  real phi = real(2) * PI * u.y;
  real p1 = r * cos(phi);
  real p2 = r * sin(phi);
  real s = real(0.5) * (real(1) + vh.z);
  p2 = (real(1) - s) * safeSqrt(real(1) - p1 * p1) + s * p2;
  vec3 nh = t1 * p1 + t2 * p2 + vh * safeSqrt(real(1) - p1 * p1 - p2 * p2);
  return normalize(vec3(alpha.x * nh.x, alpha.y * nh.y, max(nh.z, real(1e-7))));
}

// GGX D(h) in solid angle for a local half vector (0 below the surface).
real ggxDensityLocal(vec3 h, vec2 alpha) {
  if (!(h.z > real(0))) return real(0);
  vec2 s = vec2(h.x, h.y) / h.z;
  return slopeDensity(NDF_GGX, s, alpha) * slopeToSolidAngle(s);
}

// Density in solid angle of the light direction l = reflect(-v, h) when h is
// a visible normal: D_v(h) / (4 v.h) = G1(v) D(h) / (4 v.z).
real ggxReflectedPdf(vec3 v, vec3 l, vec2 alpha) {
  if (!(v.z > real(0))) return real(0);
  vec3 h = safeNormalize(v + l, vec3(real(0), real(0), real(1)));
  real g1 = real(1) / (real(1) + ggxLambda(v, clampAlpha(alpha)));
  return g1 * ggxDensityLocal(h, clampAlpha(alpha)) / (real(4) * v.z);
}

// Everything the light integral of one pixel sample needs.
struct SgShadingPoint {
  SG light;      // world space
  vec3 t, b, n;  // shading frame (world)
  vec3 ng;       // geometric normal
  vec3 v;        // local view (shading frame)
  int variant;
  int ndf;
  vec2 alpha;     // the material's
  vec2 alphaEff;  // the variant's at the pixel: G2 and the sampling lobe
  vec3 f0;
  ShadingFootprint f;
  VariantParams vp;
};

vec3 toWorld(SgShadingPoint p, vec3 d) { return p.t * d.x + p.b * d.y + p.n * d.z; }

// D G2 F / (4 n.v) L(l) for the local light direction l: the integrand.
vec3 sgIntegrand(SgShadingPoint p, vec3 l) {
  vec3 z = vec3(real(0), real(0), real(0));
  vec3 lw = toWorld(p, l);
  if (!(l.z > real(0)) || !(dot(lw, p.ng) > real(0)) || !(p.v.z > real(0))) return z;
  vec3 h = safeNormalize(p.v + l, vec3(real(0), real(0), real(1)));
  if (!(h.z > real(0))) return z;
  ShadingFootprint f = p.f;
  f.hpp = vec2(h.x, h.y) / h.z;
  real d = variantAt(p.variant, p.ndf, p.alpha, f, p.vp).density;
  real g = smithG2(p.ndf, p.v, l, p.alphaEff);
  return schlickFresnel(p.f0, sat(dot(p.v, h))) * (d * g / (real(4) * p.v.z)) * sgEvaluate(p.light, lw);
}

// Balance-heuristic contribution of direction l (local) drawn by either strategy.
vec3 sgMisTerm(SgShadingPoint p, vec3 l) {
  real pdf = sgDirectionPdf(p.light, toWorld(p, l)) + ggxReflectedPdf(p.v, l, p.alphaEff);
  if (!(pdf > real(0))) return vec3(real(0), real(0), real(0));
  return sgIntegrand(p, l) / pdf;
}

vec3 toLocal(SgShadingPoint p, vec3 d) { return vec3(dot(d, p.t), dot(d, p.b), dot(d, p.n)); }

// The irradiance int L(l) (n.l)+ dl estimated from one SG direction (uLight):
// L / pdf is the SG's mass, so the estimate is that mass times (n.l)+.
vec3 sgIrradianceEstimate(SG g, vec3 n, vec2 uLight) {
  vec3 l = sgSampleDirection(g, uLight);
  real lambda = max(g.sharpness, real(0));
  return g.amplitude * (real(4) * PI * oneMinusExpNegOver(real(2) * lambda) * max(dot(n, l), real(0)));
}

// Point i of the Fibonacci lattice (i / n, i g / n mod 1), shifted by half a
// cell so that no point sits on the sampling maps' edges (u = 0 is a pole).
vec2 latticePoint(int i) {
  int j = (i * SG_QUADRATURE_GENERATOR) - ((i * SG_QUADRATURE_GENERATOR) / SG_QUADRATURE_POINTS) * SG_QUADRATURE_POINTS;
  return vec2((real(i) + real(0.5)) / real(SG_QUADRATURE_POINTS), (real(j) + real(0.5)) / real(SG_QUADRATURE_POINTS));
}

// The specular integral: with u.x >= 0 one direction from each strategy
// (u.xy for the SG, u.zw for the BRDF: the reference's Monte Carlo
// estimate), else the lattice's SG_QUADRATURE_POINTS of each (the BRDF's
// turned a quarter so that the two point sets do not share coordinates).
// One loop with one integrand call: every call site is a copy of the
// variant after inlining, and lavapipe's pipeline creation grows with them.
vec3 sgSpecular(SgShadingPoint p, vec4 u) {
  bool monteCarlo = u.x >= real(0);
  int n = monteCarlo ? 1 : SG_QUADRATURE_POINTS;
  vec3 sum = vec3(real(0), real(0), real(0));
  SHIMMER_DONT_UNROLL for (int k = 0; k < 2 * n; k++) {
    int i = k / 2;
    bool fromLight = k - 2 * i == 0;
    vec2 q = monteCarlo ? (fromLight ? vec2(u.x, u.y) : vec2(u.z, u.w)) : latticePoint(i);
    vec3 l;
    if (fromLight) {
      l = toLocal(p, sgSampleDirection(p.light, q));
    } else {
      if (!(p.v.z > real(0))) continue;
      l = reflectAbout(p.v, sampleGgxVisibleNormal(p.v, clampAlpha(p.alphaEff), vec2(q.y, q.x)));
    }
    sum += sgMisTerm(p, l);
  }
  return sum / real(n);
}

// int_0^{2 pi} max(A + B cos phi, 0) dphi, B >= 0.
real clampedCosineRing(real A, real B) {
  if (A >= B) return real(2) * PI * A;
  if (A <= -B) return real(0);
  return real(2) * (A * acos(clamp(-A / B, real(-1), real(1))) + safeSqrt(B * B - A * A));
}

real gaussLegendre8Node(int i) {
  if (i == 0) return real(-0.9602898564975363);
  if (i == 1) return real(-0.7966664774136267);
  if (i == 2) return real(-0.5255324099163290);
  if (i == 3) return real(-0.1834346424956498);
  if (i == 4) return real(0.1834346424956498);
  if (i == 5) return real(0.5255324099163290);
  if (i == 6) return real(0.7966664774136267);
  return real(0.9602898564975363);
}
real gaussLegendre8Weight(int i) {
  if (i == 0 || i == 7) return real(0.1012285362903763);
  if (i == 1 || i == 6) return real(0.2223810344533745);
  if (i == 2 || i == 5) return real(0.3137066458778873);
  return real(0.3626837833783620);
}

// int_ta^tb e^(lambda (cos t - 1)) sin t ring(t) dt by 8-point Gauss-Legendre.
real sgIrradiancePiece(real ta, real tb, real lambda, real cb, real sb) {
  if (!(tb > ta)) return real(0);
  real sum = real(0);
  for (int i = 0; i < 8; i++) {
    real t = real(0.5) * (ta + tb) + real(0.5) * (tb - ta) * gaussLegendre8Node(i);
    real h = sin(real(0.5) * t);
    real weight = exp(real(-2) * lambda * h * h) * sin(t);  // cos t - 1 = -2 sin^2(t / 2): no cancellation
    sum += gaussLegendre8Weight(i) * weight * clampedCosineRing(cb * cos(t), sb * sin(t));
  }
  return real(0.5) * (tb - ta) * sum;
}

// Irradiance int L(l) (n.l)+ dl of the SG light on unit normal n, in the
// angle t from the SG's axis: E = a int_0^pi e^(lambda (cos t - 1)) sin t
// ring(t) dt, ring the clamped-cosine integral over the azimuth (closed
// form). The angle is the variable in which sin and cos stay smooth at both
// poles; the rule is split at multiples of the lobe's width 1 / sqrt(lambda)
// (beyond 12 widths the lobe is below e^-37 of its peak) and at ring's kinks
// cos t = +-sin b (b the angle from the normal to the axis), so that every
// piece is smooth.
vec3 sgIrradiance(SG g, vec3 n) {
  real lambda = max(g.sharpness, real(0));
  real cb = clamp(dot(n, g.axis), real(-1), real(1));
  real sb = safeSqrt(real(1) - cb * cb);
  real w = inversesqrt(max(lambda, real(1e-6)));
  real k1 = acos(min(sb, real(1)));
  real k2 = PI - k1;
  real ends[4];
  ends[0] = real(0);
  ends[1] = real(1.5) * w;
  ends[2] = real(4) * w;
  ends[3] = real(12) * w;
  real total = real(0);
  for (int i = 0; i < 3; i++) {
    real a = min(ends[i], PI);
    real b = min(ends[i + 1], PI);
    if (!(b > a)) continue;
    real m1 = clamp(k1, a, b);
    real m2 = clamp(k2, a, b);
    total += sgIrradiancePiece(a, m1, lambda, cb, sb) + sgIrradiancePiece(m1, m2, lambda, cb, sb) +
             sgIrradiancePiece(m2, b, lambda, cb, sb);
  }
  return g.amplitude * total;
}
