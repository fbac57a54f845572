// The microfacet BRDF the renderer shades with: f = D G F / (4 n.l n.v),
// D the variant's filtered NDF, G the height-correlated Smith masking-shadowing
// of the same family with the variant's effective roughness, F Schlick's
// Fresnel. Directions are unit vectors in the shading tangent frame
// (x = tangent, y = bitangent, z = shading normal).

// Smith Lambda of the anisotropic GGX distribution (Heitz 2014, eq. 72 with
// the projected roughness alpha_o^2 = ax^2 wx^2 + ay^2 wy^2 over sin^2).
real ggxLambda(vec3 w, vec2 alpha) {
  real z2 = max(w.z * w.z, real(1e-12));
  real a2tan2 = (sqr(alpha.x * w.x) + sqr(alpha.y * w.y)) / z2;
  return (sqrt(real(1) + a2tan2) - real(1)) * real(0.5);
}

// Smith Lambda of Beckmann, Walter et al. 2007 rational fit (exact within 0.35%).
real beckmannLambda(vec3 w, vec2 alpha) {
  real s = sqrt(sqr(alpha.x * w.x) + sqr(alpha.y * w.y));
  if (!(s > real(1e-12))) return real(0);
  real a = abs(w.z) / s;
  if (a >= real(1.6)) return real(0);
  return (real(1) - real(1.259) * a + real(0.396) * a * a) / (real(3.535) * a + real(2.181) * a * a);
}

real smithLambda(int ndf, vec3 w, vec2 alpha) {
  alpha = clampAlpha(alpha);
  // Blinn-Phong takes Beckmann's Lambda at the same alpha (Walter et al. 2007).
  if (ndf == NDF_BECKMANN || ndf == NDF_BLINN_PHONG || ndf == NDF_GLINTS) return beckmannLambda(w, alpha);
  return ggxLambda(w, alpha);
}

// Height-correlated masking-shadowing G2 = 1 / (1 + Lambda(v) + Lambda(l)).
real smithG2(int ndf, vec3 v, vec3 l, vec2 alpha) {
  return real(1) / (real(1) + smithLambda(ndf, v, alpha) + smithLambda(ndf, l, alpha));
}

vec3 schlickFresnel(vec3 f0, real vdoth) {
  real m = sat(real(1) - vdoth);
  real m5 = m * m * m * m * m;
  return f0 + (vec3(real(1), real(1), real(1)) - f0) * m5;
}

// Specular radiance D G F Li / (4 n.v) (the n.l of the BRDF and of the
// irradiance cancel). `density` is the variant's D(h) in solid angle.
vec3 specularRadiance(int ndf, real density, vec2 alphaEff, vec3 f0, vec3 vLocal, vec3 lLocal, real vdoth,
                      vec3 irradiance) {
  if (!(vLocal.z > real(0)) || !(lLocal.z > real(0))) return vec3(real(0), real(0), real(0));
  real g = smithG2(ndf, vLocal, lLocal, alphaEff);
  return schlickFresnel(f0, vdoth) * (density * g / (real(4) * vLocal.z)) * irradiance;
}

vec3 diffuseRadiance(vec3 albedo, real ndotl, vec3 irradiance) {
  return albedo * (max(ndotl, real(0)) / PI) * irradiance;
}
