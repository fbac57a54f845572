// shimmer shading core: shared constants and small numeric helpers.
//
// Every .glsl file in this folder is compiled twice: to SPIR-V for the
// renderer's kernels (with `#define real float`) and to C++ through
// glsl_compat.h, once with real = float and once with real = double. So the
// files keep to the subset both languages accept:
//   - no swizzles (write vec2(v.x, v.y)), no out/inout parameters,
//     no array constructors, no struct constructors (assign fields);
//   - literals mixed with `real` values are wrapped: real(2) * x, max(x, real(0)).

const real PI = real(3.14159265358979323846);
const real HALF_PI = real(1.57079632679489661923);

// Roughness is clamped from below so that 1 / (pi * ax * ay) stays finite in
// float; 1e-4 is ten times sharper than the sharpest material the tests use.
const real ALPHA_MIN = real(1e-4);
// And from above, so that alpha^2 and its sums stay finite for any input
// (physical roughness ends at 1; engines clamp there too).
const real ALPHA_MAX = real(100);
// Slopes beyond this are treated as this (density there is zero in float and
// double alike); keeps (1 + |s|^2)^2 finite in float.
const real SLOPE_MAX = real(1e8);

real sqr(real x) { return x * x; }
real sat(real x) { return clamp(x, real(0), real(1)); }
real safeSqrt(real x) { return sqrt(max(x, real(0))); }

vec2 clampAlpha(vec2 a) { return clamp(a, vec2(ALPHA_MIN, ALPHA_MIN), vec2(ALPHA_MAX, ALPHA_MAX)); }

vec2 clampSlope(vec2 s) {
  real m = max(abs(s.x), abs(s.y));
  if (m > SLOPE_MAX) return s * (SLOPE_MAX / m);
  return s;
}

// normalize() that keeps `fallback` for a (near) zero vector instead of NaN.
// A vector longer than ~1e19 squares to Inf in float, and inversesqrt(Inf)
// would turn it into the zero vector; it is scaled down first.
vec3 safeNormalize(vec3 v, vec3 fallback) {
  real len2 = dot(v, v);
  if (len2 > real(1e30)) {
    v = v / max(abs(v.x), max(abs(v.y), abs(v.z)));
    len2 = dot(v, v);
  }
  if (!(len2 > real(1e-30))) return fallback;
  return v * inversesqrt(len2);
}
