// Filters the slope density itself instead of widening alpha: the NDF's
// slope-space density P22 averaged over the pixel's footprint rectangle with
// a 5-tap rule (the centre with weight 1/2, the four corners with 1/8 each).
// The footprint half-sides are clamped to fp_max; with fp_max = 0 it is the
// unfiltered NDF. docs/variants.md explains every name.
// shimmer-variant: P22 averaged over the footprint rectangle by a 5-tap rule
// shimmer-param: fp_max = 1 in [0, 10000]: clamp on the footprint's slope-space half-sides
FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {
  vec2 a = clampAlpha(alpha);
  vec2 s = clampSlope(f.hpp);
  vec2 h = min(footprintHalfSides(f), vec2(p.fp_max, p.fp_max));
  real corners = slopeDensity(ndf, s + h, a) + slopeDensity(ndf, s - h, a) +
                 slopeDensity(ndf, s + vec2(h.x, -h.y), a) + slopeDensity(ndf, s + vec2(-h.x, h.y), a);
  FilteredNdf r;
  r.slope_density = real(0.5) * slopeDensity(ndf, s, a) + real(0.125) * corners;
  r.density = r.slope_density * slopeToSolidAngle(s);  // P22 / h.z^4: the solid-angle D(h)
  r.alpha_eff = a;  // the shadowing term keeps the material's roughness
  return r;
}
