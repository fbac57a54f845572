// Tokuyoshi and Kaplanyan 2019 in the form engines ship (the built-in `tk19`),
// written as a user variant: it widens alpha.
//   alpha'^2 = sat(alpha^2 + min(2 sigma2 S, kappa)),  S = |dn/dx|^2 + |dn/dy|^2
// docs/variants.md explains every name used here.
// shimmer-variant: Tokuyoshi-Kaplanyan 2019 as engines ship it (the built-in tk19), as a user file
// shimmer-param: sigma2 = 0.25 in [0, 10000]: screen-space variance of the filtering kernel
// shimmer-param: kappa = 0.18 in [0, 10000]: clamp on the kernel roughness
FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {
  vec2 a = clampAlpha(alpha);  // as every built-in variant does first
  real spread = normalSpread(f.dn_dx, f.dn_dy);
  real k = min(real(2) * p.sigma2 * spread, p.kappa);
  vec2 a2 = a * a + vec2(k, k);
  return widenedNdf(ndf, clampSlope(f.hpp), vec2(sat(a2.x), sat(a2.y)));
}
