// Normal distribution functions in slope space (P22) and in solid angle.
//
// Slope space: a microfacet normal m = normalize(-sx, -sy, 1) has slope
// s = (sx, sy) = m.xy / m.z (seed 000: "half vector in parallel plane
// domain"). D(m) = P22(s) / m.z^4, so that the integral of D(m) (n.m) over the
// hemisphere equals the integral of P22 over the plane, which is 1.

const int NDF_GGX = 0;
const int NDF_BECKMANN = 1;
// Blinn-Phong, D = (s + 2) / (2 pi) (n.h)^s, the NDF seed 003 writes its
// formulas for, with the power s = 2 / alpha^2 - 2 of Walter et al. 2007
// (the materials give alpha; `blinn-phong:S` in a material spec converts).
const int NDF_BLINN_PHONG = 2;
// Glints (glints.glsl): Beckmann microdetail slopes with a local lobe; where
// a smooth density is asked of it, the global NDF, which is Beckmann.
const int NDF_GLINTS = 3;

// Anisotropic GGX (Trowbridge-Reitz) slope density.
real ggxP22(vec2 s, vec2 a) {
  real x = s.x / a.x;
  real y = s.y / a.y;
  real t = real(1) + x * x + y * y;
  return real(1) / (PI * a.x * a.y * t * t);
}

// Anisotropic Beckmann slope density: a 2D Gaussian with variance a^2 / 2 per axis.
real beckmannP22(vec2 s, vec2 a) {
  real x = s.x / a.x;
  real y = s.y / a.y;
  return exp(-(x * x + y * y)) / (PI * a.x * a.y);
}

// log(1 + x) for x >= 0 to full relative precision (GLSL has no log1p):
// 1 + x rounds away x's low digits, which the Blinn-Phong exponent (1/m,
// up to 1e8) would magnify. Below 0.5, 2 atanh(z) with z = x / (2 + x) <= 0.2
// by its series (truncation below 1e-9); above, log(1 + x) is exact enough.
real log1pSafe(real x) {
  if (x >= real(0.5)) return log(real(1) + x);
  real z = x / (real(2) + x);
  real z2 = z * z;
  return real(2) * z *
         (real(1) + z2 * (real(1) / real(3) +
                          z2 * (real(0.2) + z2 * (real(1) / real(7) + z2 * (real(1) / real(9) + z2 / real(11))))));
}

// Blinn-Phong's slope density, given q = s^T R^-1 s and det R (R = diag(a^2)
// for an axis-aligned lobe): with m = sqrt(det R) (alpha^2 of an isotropic
// lobe) and power 2/m - 2, P22 = (1 + m q)^-(1/m + 1) / (pi sqrt(det R)).
// Normalised for every m; it tends to Beckmann's exp(-q) as m -> 0.
// Anisotropic lobes are the isotropic one stretched per axis.
real blinnPhongP22Quadratic(real q, real det) {
  real m = sqrt(det);
  return exp(-(real(1) / m + real(1)) * log1pSafe(m * q)) / (PI * m);
}

real blinnPhongP22(vec2 s, vec2 a) {
  real x = s.x / a.x;
  real y = s.y / a.y;
  return blinnPhongP22Quadratic(x * x + y * y, sqr(a.x * a.y));
}

real slopeDensity(int ndf, vec2 s, vec2 a) {
  a = clampAlpha(a);
  s = clampSlope(s);
  if (ndf == NDF_BECKMANN || ndf == NDF_GLINTS) return beckmannP22(s, a);
  if (ndf == NDF_BLINN_PHONG) return blinnPhongP22(s, a);
  return ggxP22(s, a);
}

// Slope density of a distribution with roughness matrix R, given the
// quadratic form q = s^T R^-1 s and det R (seed 000_16155bfd1e3ea941.txt,
// "Filtering Beckmann": R' = R + 2C). For GGX the same quadratic form
// generalises the ellipsoid NDF to an arbitrary orientation. q >= 0, det > 0.
real slopeDensityQuadratic(int ndf, real q, real det) {
  real norm = PI * sqrt(det);
  if (ndf == NDF_BECKMANN || ndf == NDF_GLINTS) return exp(-q) / norm;
  if (ndf == NDF_BLINN_PHONG) return blinnPhongP22Quadratic(q, det);
  real t = real(1) + q;
  return real(1) / (norm * t * t);
}

// 1 / h.z^4 for h = normalize(s.x, s.y, 1): the Jacobian from slope to solid angle.
real slopeToSolidAngle(vec2 s) {
  s = clampSlope(s);
  return sqr(real(1) + dot(s, s));
}
