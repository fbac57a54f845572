// Tokuyoshi and Kaplanyan 2019 in the form engines ship (the built-in `tk19`),
// written as a user variant: it widens alpha.
//   alpha'^2 = sat(alpha^2 + min(2 sigma2 S, kappa)),  S = |dn/dx|^2 + |dn/dy|^2
// Parameters: --param sigma2=V (the kernel's screen-space variance) and
// --param kappa=V (the clamp). docs/variants.md explains every name used here.
FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, VariantParams p) {
  vec2 a = clampAlpha(alpha);  // as every built-in variant does first
  real spread = normalSpread(f.dn_dx, f.dn_dy);
  real k = min(real(2) * p.sigma2 * spread, p.kappa);
  vec2 a2 = a * a + vec2(k, k);
  return widenedNdf(ndf, clampSlope(f.hpp), vec2(sat(a2.x), sat(a2.y)));
}
