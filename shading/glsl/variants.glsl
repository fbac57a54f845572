// Specular anti-aliasing filter variants: each maps the shading footprint to
// a filtered slope-space NDF value and, where it widens roughness, the
// effective roughness. Names, parameters, defaults and sources are listed for
// users in shading/variant_table.json (`shimmer variants`).

// VARIANT_*, NMF_*, VariantParams and VARIANT_PARAMS_FROM_SLOTS come from
// variant_table.glsl, generated from shading/variant_table.json.

// A variant id is a geometric filter plus NMF_STRIDE times a normal-map
// filter (NMF_*; 0 for the geometric filters alone):
// `toksvig` is NMF_TOKSVIG * NMF_STRIDE, `tk19+toksvig` adds VARIANT_TK19.
// The normal-map filter picks the shading normal and widens the material's
// roughness (pixel.glsl); the geometric filter then filters that material.
int geometricVariant(int variant) { return variant - (variant / NMF_STRIDE) * NMF_STRIDE; }
int normalMapFilterOf(int variant) { return variant / NMF_STRIDE; }

bool isSgVariant(int variant) {
  int g = geometricVariant(variant);
  return g >= VARIANT_SG_WARP && g <= VARIANT_ASG_WARP_K16;
}

// What a pixel knows about its neighbourhood. Derivatives are per pixel along
// screen x and y, from 2x2 quad differences or from ray differentials.
struct ShadingFootprint {
  vec2 hpp;      // slope-space half vector h.xy / h.z in the shading tangent frame (seed 000)
  vec2 dhpp_dx;  // d hpp / d screen x
  vec2 dhpp_dy;
  vec2 dh_dx;    // d h.xy / d screen x: the projected half vector's derivatives (TK19 forward)
  vec2 dh_dy;
  vec3 n;        // unit shading normal
  vec3 dn_dx;    // derivatives of the shading normal
  vec3 dn_dy;
  vec3 dng_dx;   // derivatives of the geometric normal (engine presets use these)
  vec3 dng_dy;
};

struct FilteredNdf {
  real slope_density;  // filtered P22 at hpp (k16-ggx-rect-jacobian: density * h.z^4)
  real density;        // slope_density / h.z^4, the solid-angle NDF D(h)
  vec2 alpha_eff;      // roughness used for the lobe (the material's where not widened)
};

// Axis-aligned rectangle bounding the footprint parallelogram: half-sides
// (|dx hpp| + |dy hpp|) / 2 (seed 000 "More Temporal Stability"; seed 001).
vec2 footprintHalfSides(ShadingFootprint f) {
  return (abs(f.dhpp_dx) + abs(f.dhpp_dy)) * real(0.5);
}

// Spread of the normals over the pixel, S = |dn/dx|^2 + |dn/dy|^2 (seed
// 000_16155bfd1e3ea941.txt: "look at the spread of shading normals
// (ddx/ddy)"). Saturated at SPREAD_MAX: derivatives beyond ~1e19 per pixel
// square to Inf in float, and the kernels' sigma2 S is then NaN for sigma2 = 0.
// The kernels are min(c sigma2 S, kappa) with c >= 1 and kappa <= 1e4
// (ParamRanges), so a spread of 1e30 already saturates them for any sigma2
// above 1e-26, and c sigma2 S stays finite in float for sigma2 <= 1e4.
const real SPREAD_MAX = real(1e30);
real normalSpread(vec3 dx, vec3 dy) { return min(dot(dx, dx) + dot(dy, dy), SPREAD_MAX); }

FilteredNdf widenedNdf(int ndf, vec2 hpp, vec2 alpha2) {
  FilteredNdf r;
  r.alpha_eff = sqrt(alpha2);
  r.slope_density = slopeDensity(ndf, hpp, r.alpha_eff);
  r.density = r.slope_density * slopeToSolidAngle(hpp);
  return r;
}

// Seed 000, "Filtering Beckmann" with the axis-aligned rect: a Gaussian pixel
// filter of 0.5 px standard deviation has slope-space std fp, and Beckmann
// roughness is sqrt(2) std, so alpha^2 += 2 fp^2, fp clamped to fp_max.
vec2 k16RectAlpha2(vec2 alpha, ShadingFootprint f, real fpMax) {
  vec2 fp = min(footprintHalfSides(f), vec2(fpMax, fpMax));
  return alpha * alpha + real(2) * fp * fp;
}

// Seed 000, "Filtering Beckmann" with the full parallelogram: R' = R + 2 C,
// C = U U^T. U holds the two propagated standard-deviation vectors of the
// Gaussian pixel filter of variance sigma2 px^2: sqrt(sigma2) times the
// per-pixel derivatives. At the default sigma2 = 1/4 (0.5 px) the
// parallelogram and the rect agree on axis-aligned footprints; sigma2 = 1 is
// the slide's bare U = dh/duv, which widens four times as much.
//
// det R' and the form s^T adj(R') s are written as sums of squares (adj is
// linear on 2x2 matrices and adj(U U^T) = adj(U)^T adj(U)):
//   det R' = ax^2 ay^2 + 2 (ay^2 C_xx + ax^2 C_yy) + 4 det(U)^2,
//   s^T adj(R') s = ay^2 s.x^2 + ax^2 s.y^2 + 2 (cross(s, ux)^2 + cross(s, uy)^2).
// For a nearly rank-one footprint (dx hpp ~ parallel to dy hpp, or both clamped
// to FOOTPRINT_MAX) the textbook r00 r11 - r01^2 cancels in float to anything,
// and a form that rounds to zero or below made the density Inf far from the
// lobe (seed 000_16155bfd1e3ea941.txt gives R' only, not how to evaluate it).
real cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

FilteredNdf k16Parallelogram(int ndf, vec2 alpha, ShadingFootprint f, real sigma2) {
  real u = sqrt(max(sigma2, real(0)));
  vec2 ux = u * f.dhpp_dx;
  vec2 uy = u * f.dhpp_dy;
  vec2 s = clampSlope(f.hpp);
  real ax2 = alpha.x * alpha.x;
  real ay2 = alpha.y * alpha.y;
  real cxx = ux.x * ux.x + uy.x * uy.x;
  real cyy = ux.y * ux.y + uy.y * uy.y;
  real detU = cross2(ux, uy);
  real det = ax2 * ay2 + real(2) * (ay2 * cxx + ax2 * cyy) + real(4) * detU * detU;
  real cx = cross2(s, ux);
  real cy = cross2(s, uy);
  real form = ay2 * s.x * s.x + ax2 * s.y * s.y + real(2) * (cx * cx + cy * cy);
  FilteredNdf o;
  o.alpha_eff = sqrt(vec2(ax2 + real(2) * cxx, ay2 + real(2) * cyy));
  o.slope_density = slopeDensityQuadratic(ndf, form / det, det);
  o.density = o.slope_density * slopeToSolidAngle(s);
  return o;
}

// Vlachos, "Advanced VR Rendering" (GDC 2015), as cited in seed 000 and as in
// Valve's The Lab renderer: perceptual roughness r = sqrt(alpha) is clamped
// from below by pow(sat(max(|dn/dx|^2, |dn/dy|^2)), 0.333) of the geometric
// normal. Unreal's "normal curvature to roughness" exposes the constants:
// sat(S pow(max(...), E) + B), which is Vlachos' at S = 1, B = 0, E = 0.333.
vec2 vlachosAlpha2(vec2 alpha, ShadingFootprint f, VariantParams p) {
  real c = max(dot(f.dng_dx, f.dng_dx), dot(f.dng_dy, f.dng_dy));
  // Bounded so that S = 0 times an overflowed power stays 0, not NaN.
  real t = min(pow(min(c, real(1e30)), p.curvature_exponent), real(1e30));
  real k = sat(p.curvature_scale * t + p.curvature_bias);
  vec2 r = max(sqrt(alpha), vec2(k, k));
  vec2 a = r * r;
  return a * a;
}

// Toksvig (2004) as in seed 003: sigma^2 = (1 - |Na|) / |Na| from the length
// of the averaged normal, and p = s / (1 + s sigma^2) on the Blinn-Phong
// power, i.e. alpha^2 += 2 sigma^2 in Beckmann terms (alpha^2 ~ 2 / s). Na is
// the mean of the four normals of the 2x2 quad around the pixel, rebuilt from
// the derivatives. 1 - |Na|^2 = (1/16) sum_{i<j} |n_i - n_j|^2 avoids the
// cancellation of 1 - |Na| for nearly parallel normals.
vec2 toksvigAlpha2(vec2 alpha, ShadingFootprint f) {
  vec3 hx = real(0.5) * f.dn_dx;
  vec3 hy = real(0.5) * f.dn_dy;
  vec3 n0 = safeNormalize(f.n - hx - hy, f.n);
  vec3 n1 = safeNormalize(f.n + hx - hy, f.n);
  vec3 n2 = safeNormalize(f.n - hx + hy, f.n);
  vec3 n3 = safeNormalize(f.n + hx + hy, f.n);
  real spread = dot(n0 - n1, n0 - n1) + dot(n0 - n2, n0 - n2) + dot(n0 - n3, n0 - n3) +
                dot(n1 - n2, n1 - n2) + dot(n1 - n3, n1 - n3) + dot(n2 - n3, n2 - n3);
  real oneMinusLen2 = min(spread / real(16), real(1));
  real len = sqrt(real(1) - oneMinusLen2);
  vec2 a2 = alpha * alpha;
  if (len < real(1e-6)) return max(a2, vec2(1, 1));
  real sigma2 = oneMinusLen2 / ((real(1) + len) * len);
  return max(a2, min(a2 + real(2) * sigma2, vec2(1, 1)));
}

// Tokuyoshi and Kaplanyan, "Improved Geometric Specular Antialiasing"
// (I3D 2019), in the form engines ship: alpha'^2 = sat(alpha^2 + min(2 sigma2 S, kappa)),
// S = |dn/dx|^2 + |dn/dy|^2. Engine presets differ in the constants and in
// which normal they differentiate.
vec2 tk19Alpha2(vec2 alpha, real spread, real sigma2, real kappa) {
  real k = min(real(2) * sigma2 * spread, kappa);
  vec2 a2 = alpha * alpha + vec2(k, k);
  return vec2(sat(a2.x), sat(a2.y));
}

// Tokuyoshi and Kaplanyan, "Improved Geometric Specular Antialiasing" (I3D
// 2019), forward rendering. Seed 000's kernel is a Gaussian in slope space
// whose bandwidth comes from the screen derivatives of the slope h.xy / h.z;
// where h.z is small (grazing angles, silhouettes) a finite difference of the
// slope is dominated by its error. The paper takes the bandwidth from the
// derivatives of the projected half vector h.xy instead, which stays in the
// unit disk: Sigma = sigma2 (dx dx^T + dy dy^T) with dx = d h.xy / d screen x,
// the kernel roughness 2 Sigma clamped to kappa, added to the roughness
// matrix (alpha^2 on its diagonal) and the NDF evaluated with the result, not
// axis-aligned in general. The paper's deferred form is `tk19`.
//
// The paper clamps a scalar kernel, min(2 sigma2 x, kappa); the matrix is
// clamped here in its eigenvalues, which is the same on each axis of a
// diagonal kernel and does not depend on the tangent frame. With the kernel
// K = 2 Sigma, lambda+- its eigenvalues, the clamped kernel is mu I + c K:
//   (mu, c) = (0, 1)                          lambda+ <= kappa,
//           = ((1 - c) lambda-, (kappa - lambda-) / (lambda+ - lambda-))
//                                             lambda- < kappa < lambda+,
//           = (kappa, 0)                      lambda- >= kappa,
// which keeps the smaller eigenvalue and its axis. det and s^T adj s are then
// sums of non-negative terms (adj is linear on 2x2 matrices), as in
// k16Parallelogram, so a nearly rank-one kernel does not cancel in float.
FilteredNdf tk19Forward(int ndf, vec2 alpha, ShadingFootprint f, real sigma2, real kappa) {
  real w = real(2) * max(sigma2, real(0));
  vec2 dx = f.dh_dx;
  vec2 dy = f.dh_dy;
  real kxx = w * (dx.x * dx.x + dy.x * dy.x);
  real kyy = w * (dx.y * dx.y + dy.y * dy.y);
  real kxy = w * (dx.x * dx.y + dy.x * dy.y);
  real cr = cross2(dx, dy);
  real detK = w * w * cr * cr;
  real mid = real(0.5) * (kxx + kyy);
  real lmax = mid + sqrt(sqr(real(0.5) * (kxx - kyy)) + kxy * kxy);
  real lmin = lmax > real(0) ? detK / lmax : real(0);
  real mu = real(0);
  real c = real(1);
  if (lmin >= kappa) {
    mu = kappa;
    c = real(0);
  } else if (lmax > kappa) {
    c = (kappa - lmin) / (lmax - lmin);
    mu = (real(1) - c) * lmin;
  }
  vec2 s = clampSlope(f.hpp);
  real ax2 = alpha.x * alpha.x;
  real ay2 = alpha.y * alpha.y;
  real rxx = ax2 + mu + c * kxx;
  real ryy = ay2 + mu + c * kyy;
  real detKc = mu * mu + mu * c * (kxx + kyy) + c * c * detK;
  real det = ax2 * ay2 + ay2 * (mu + c * kxx) + ax2 * (mu + c * kyy) + detKc;
  real cx = cross2(s, dx);
  real cy = cross2(s, dy);
  real form = ay2 * s.x * s.x + ax2 * s.y * s.y + mu * dot(s, s) + c * w * (cx * cx + cy * cy);
  FilteredNdf o;
  o.alpha_eff = sqrt(vec2(rxx, ryy));
  o.slope_density = slopeDensityQuadratic(ndf, form / det, det);
  o.density = o.slope_density * slopeToSolidAngle(s);
  return o;
}

// The same paper's axis-aligned form: the kernel from the bounding rectangle
// |dx| + |dy| of the projected half vector's derivatives, per axis,
// alpha'^2 = sat(alpha^2 + min(2 sigma2 b^2, kappa)).
vec2 tk19ForwardRectAlpha2(vec2 alpha, ShadingFootprint f, real sigma2, real kappa) {
  vec2 b = abs(f.dh_dx) + abs(f.dh_dy);
  vec2 k = min(real(2) * sigma2 * b * b, vec2(kappa, kappa));
  vec2 a2 = alpha * alpha + k;
  return vec2(sat(a2.x), sat(a2.y));
}

// Tokuyoshi and Kaplanyan, "Stable Geometric Specular Antialiasing with
// Projected-Space NDF Filtering" (JCGT 2021): p = alpha^2 / (1 - alpha^2),
// p' = p + min(sigma2 S, kappa), alpha'^2 = p' / (1 + p'). Written as
// (alpha^2 + k (1 - alpha^2)) / (1 + k (1 - alpha^2)), which is the same and
// has no pole at alpha = 1.
vec2 tk21Alpha2(vec2 alpha, real spread, real sigma2, real kappa) {
  real k = min(sigma2 * spread, kappa);
  vec2 a2 = min(alpha * alpha, vec2(1, 1));
  vec2 km = k * (vec2(1, 1) - a2);
  return (a2 + km) / (vec2(1, 1) + km);
}

// Godot 4 (scene shaders, roughness limiter): the tk19 kernel added to
// roughness2 = r * r of the perceptual roughness r, which is alpha, not alpha^2.
vec2 godotAlpha2(vec2 alpha, real spread, real sigma2, real kappa) {
  real k = min(real(2) * sigma2 * spread, kappa);
  vec2 a = min(alpha + vec2(k, k), vec2(1, 1));
  return a * a;
}

// The pixel footprint folded into the NDF's SG (sg-warp-k16, asg-warp-k16):
// the SG exp(lambda (cos t - 1)) ~ exp(-t^2 / alpha^2) with lambda = 2 / alpha^2
// has variance alpha^2 / 2 per axis; seed 000's rect footprint (half-sides
// clamped to fp_max) is a Gaussian of variance fp^2 per axis. Convolving the
// two, with the footprint made isotropic by averaging its axes, adds their
// variances: alpha'^2 = alpha^2 + fp.x^2 + fp.y^2, i.e. 1 / lambda' = 1 / lambda
// + 1 / lambda_fp with lambda_fp = 2 / (fp.x^2 + fp.y^2).
real sgFootprintVariance(ShadingFootprint f, real fpMax) {
  vec2 fp = min(footprintHalfSides(f), vec2(fpMax, fpMax));
  return dot(fp, fp);
}

// Slope-space footprints beyond 1e4 per pixel (silhouettes) filter as much as
// 1e4 does; capping them keeps squared covariances finite in float.
const real FOOTPRINT_MAX = real(1e4);

// The projected half vector h.xy of the slope s = h.xy / h.z (h.z > 0), and
// the change of h.xy for a change ds of the slope:
// d h.xy = (ds - s (s . ds) / q) / sqrt(q), q = 1 + |s|^2, with ds capped
// as evalVariant caps the slope's derivatives.
vec2 projectedHalfVector(vec2 s) {
  s = clampSlope(s);
  return s * inversesqrt(real(1) + dot(s, s));
}
vec2 projectedHalfVectorChange(vec2 s, vec2 ds) {
  s = clampSlope(s);
  ds = clamp(ds, vec2(-FOOTPRINT_MAX, -FOOTPRINT_MAX), vec2(FOOTPRINT_MAX, FOOTPRINT_MAX));
  real q = real(1) + dot(s, s);
  return (ds - s * (dot(s, ds) / q)) * inversesqrt(q);
}

FilteredNdf evalVariant(int variant, int ndf, vec2 alpha, ShadingFootprint f, VariantParams p) {
  variant = geometricVariant(variant);
  alpha = clampAlpha(alpha);
  vec2 lim = vec2(FOOTPRINT_MAX, FOOTPRINT_MAX);
  f.dhpp_dx = clamp(f.dhpp_dx, -lim, lim);
  f.dhpp_dy = clamp(f.dhpp_dy, -lim, lim);
  f.dh_dx = clamp(f.dh_dx, -lim, lim);
  f.dh_dy = clamp(f.dh_dy, -lim, lim);
  vec2 hpp = clampSlope(f.hpp);
  if (variant == VARIANT_VLACHOS15) return widenedNdf(ndf, hpp, vlachosAlpha2(alpha, f, p));
  if (variant == VARIANT_TOKSVIG_QUAD) return widenedNdf(ndf, hpp, toksvigAlpha2(alpha, f));
  if (variant == VARIANT_K16_BECKMANN_RECT || variant == VARIANT_K16_GGX_PROXY)
    return widenedNdf(ndf, hpp, k16RectAlpha2(alpha, f, p.fp_max));
  if (variant == VARIANT_K16_BECKMANN_PARALLELOGRAM) return k16Parallelogram(ndf, alpha, f, p.sigma2);
  if (variant == VARIANT_TK19_FORWARD) return tk19Forward(ndf, alpha, f, p.sigma2, p.kappa);
  if (variant == VARIANT_TK19_FORWARD_RECT) return widenedNdf(ndf, hpp, tk19ForwardRectAlpha2(alpha, f, p.sigma2, p.kappa));
  if (variant == VARIANT_K16_GGX_RECT) {
    // Seed 000 as published: footprint clamped to [min(alpha, 0.1), fp_max]
    // and the Jacobian 1 / max(1e-3, h.z^4). Where the formula cancels to a
    // negative value, or to 0/0 when x2 - x1 rounds to zero far from the
    // lobe, the result is cut to zero so that no pixel goes negative or NaN.
    vec2 fpMin = min(alpha, vec2(p.fp_min_cap, p.fp_min_cap));
    vec2 fp = clamp(footprintHalfSides(f), fpMin, max(fpMin, vec2(p.fp_max, p.fp_max)));
    FilteredNdf r;
    r.alpha_eff = alpha;
    real v = ggxRectMeanSeed(hpp, alpha, fp);
    r.slope_density = (v > real(0) && v < real(1e30)) ? v : real(0);
    r.density = r.slope_density / max(real(1e-3), real(1) / slopeToSolidAngle(hpp));
    return r;
  }
  if (variant == VARIANT_K16_GGX_RECT_STABLE) {
    vec2 fp = min(footprintHalfSides(f), vec2(p.fp_max, p.fp_max));
    FilteredNdf r;
    r.alpha_eff = alpha;
    r.slope_density = ggxRectMeanStable(hpp, alpha, fp);
    r.density = r.slope_density * slopeToSolidAngle(hpp);
    return r;
  }
  if (variant == VARIANT_K16_GGX_RECT_JACOBIAN) {
    // The footprint mean of D itself (ggx_rect.glsl): no Jacobian of the
    // centre. slope_density keeps density = slope_density / h.z^4 at hpp.
    vec2 fp = min(footprintHalfSides(f), vec2(p.fp_max, p.fp_max));
    FilteredNdf r;
    r.alpha_eff = alpha;
    r.density = ggxRectMeanJacobian(hpp, alpha, fp);
    r.slope_density = r.density / slopeToSolidAngle(hpp);
    return r;
  }
  if (variant == VARIANT_TK19)
    return widenedNdf(ndf, hpp, tk19Alpha2(alpha, normalSpread(f.dn_dx, f.dn_dy), p.sigma2, p.kappa));
  if (variant == VARIANT_TK21)
    return widenedNdf(ndf, hpp, tk21Alpha2(alpha, normalSpread(f.dn_dx, f.dn_dy), p.sigma2, p.kappa));
  if (variant == VARIANT_FILAMENT || variant == VARIANT_UNITY_HDRP)
    return widenedNdf(ndf, hpp, tk19Alpha2(alpha, normalSpread(f.dng_dx, f.dng_dy), p.sigma2, p.kappa));
  if (variant == VARIANT_GODOT)
    return widenedNdf(ndf, hpp, godotAlpha2(alpha, normalSpread(f.dn_dx, f.dn_dy), p.sigma2, p.kappa));
  if (isSgVariant(variant)) {
    // The lobe seed 004 turns into one isotropic SG (pixel.glsl, shadeUnderSg).
    vec2 a2 = alpha * alpha;
    if (variant == VARIANT_SG_WARP_K16 || variant == VARIANT_ASG_WARP_K16) {
      real v = sgFootprintVariance(f, p.fp_max);
      a2 += vec2(v, v);
    }
    return widenedNdf(ndf, hpp, a2);
  }
  return widenedNdf(ndf, hpp, alpha * alpha);  // VARIANT_NONE: point-sampled NDF
}
