#version 460
// One invocation: one variant's filtered NDF at one footprint, in the GPU's
// float, through the same shading core and (with SHIMMER_USER_VARIANT) the
// same user file the renderer compiles. `shimmer ndf` runs it for user
// variants, whose code exists only as GLSL (render/ndf_probe.cpp).
#extension GL_GOOGLE_include_directive : require
#define real float

layout(local_size_x = 1) in;
layout(constant_id = 0) const int VARIANT_ID = 0;

// In: words 0..9 as ndf_probe.cpp writes them; out: word 10.
layout(std430, binding = 0) buffer ProbeBuf { vec4 words[]; } probe;

#include "core.glsl"

#ifdef SHIMMER_USER_VARIANT
#include "user_params.glsl"
#include "user_variant.glsl"
#endif

void main() {
  ShadingFootprint f;
  f.hpp = probe.words[0].xy;
  vec2 alpha = probe.words[0].zw;
  f.dhpp_dx = probe.words[1].xy;
  f.dhpp_dy = probe.words[1].zw;
  f.n = probe.words[2].xyz;
  int ndf = int(probe.words[2].w);
  f.dn_dx = probe.words[3].xyz;
  f.dn_dy = probe.words[4].xyz;
  f.dng_dx = probe.words[5].xyz;
  f.dng_dy = probe.words[6].xyz;
  VariantParams p;  // a user variant may read the nm_scale slot; normal maps need a scene
  VARIANT_PARAMS_FROM_SLOTS(p, probe.words[7], probe.words[8]);
  f.dh_dx = probe.words[9].xy;
  f.dh_dy = probe.words[9].zw;
#ifdef SHIMMER_USER_VARIANT
  FilteredNdf r = userVariant(ndf, alpha, f, userParams(p));
#else
  FilteredNdf r = evalVariant(VARIANT_ID, ndf, alpha, f, p);
#endif
  probe.words[10] = vec4(r.slope_density, r.density, r.alpha_eff);
}
