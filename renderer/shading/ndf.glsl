// Normal distribution functions in slope space (P22) and in solid angle.
//
// Slope space: a microfacet normal m = normalize(-sx, -sy, 1) has slope
// s = (sx, sy) = m.xy / m.z (seed 000: "half vector in parallel plane
// domain"). D(m) = P22(s) / m.z^4, so that the integral of D(m) (n.m) over the
// hemisphere equals the integral of P22 over the plane, which is 1.

const int NDF_GGX = 0;
const int NDF_BECKMANN = 1;

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

real slopeDensity(int ndf, vec2 s, vec2 a) {
  a = clampAlpha(a);
  s = clampSlope(s);
  if (ndf == NDF_BECKMANN) return beckmannP22(s, a);
  return ggxP22(s, a);
}

// Slope density of a distribution with roughness matrix R, given the
// quadratic form q = s^T R^-1 s and det R (seed 000_16155bfd1e3ea941.txt,
// "Filtering Beckmann": R' = R + 2C). For GGX the same quadratic form
// generalises the ellipsoid NDF to an arbitrary orientation. q >= 0, det > 0.
real slopeDensityQuadratic(int ndf, real q, real det) {
  real norm = PI * sqrt(det);
  if (ndf == NDF_BECKMANN) return exp(-q) / norm;
  real t = real(1) + q;
  return real(1) / (norm * t * t);
}

// Slope density with a full symmetric roughness matrix R = [[r.x, r.y], [r.y, r.z]].
// Where R is nearly singular, r.x r.z - r.y^2 and the quadratic form cancel;
// callers that know how R was built should form both without cancellation
// (k16Parallelogram does) and call slopeDensityQuadratic.
real slopeDensityMatrix(int ndf, vec2 s, vec3 r) {
  s = clampSlope(s);
  real amin2 = ALPHA_MIN * ALPHA_MIN;
  real r00 = max(r.x, amin2);
  real r11 = max(r.z, amin2);
  // Keep R positive definite when rounding makes det(R) ~ 0.
  real det = max(r00 * r11 - r.y * r.y, amin2 * amin2);
  // A form that rounds below zero would make exp(-q) overflow.
  real q = max((r11 * s.x * s.x - real(2) * r.y * s.x * s.y + r00 * s.y * s.y) / det, real(0));
  return slopeDensityQuadratic(ndf, q, det);
}

// 1 / h.z^4 for h = normalize(s.x, s.y, 1): the Jacobian from slope to solid angle.
real slopeToSolidAngle(vec2 s) {
  s = clampSlope(s);
  return sqr(real(1) + dot(s, s));
}
