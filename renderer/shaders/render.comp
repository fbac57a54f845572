#version 460
// The renderer's kernel: one dispatch shades every pixel of one frame (or one
// round, a replicate, of reference samples). Only the Vulkan-specific parts
// live here: invocation -> pixel mapping, the 2x2 quad exchange for quad
// derivatives, the sub-pixel sample loop of the reference, buffer writes.
// Everything a pixel computes is in the shading core (scene.glsl, pixel.glsl),
// which the CPU oracle runs in double.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_quad : require
#extension GL_EXT_control_flow_attributes : require
#define SHIMMER_DONT_UNROLL [[dont_unroll]]
#define real float
#define SHIMMER_SCENE_WORDS

// 64 invocations = 16 quads of 2x2 pixels = an 8x8 pixel tile.
layout(local_size_x = 64) in;

layout(constant_id = 0) const int VARIANT_ID = 0;
layout(constant_id = 1) const int DERIV_MODE = 0;  // DERIV_* of pixel.glsl
layout(constant_id = 2) const int SPP_N = 1;       // N x N stratified sub-pixel samples; 1 = pixel centre
layout(constant_id = 3) const int SCENE_FEATURES = 15;  // SCENE_* bits of scene.glsl: the primitive kinds present
// The material's NDF_* (ndf.glsl). A constant, not a frame value: the shading
// then compiles one NDF's D and Smith Lambda instead of both (the reference
// measured 5-8 % faster on lavapipe).
layout(constant_id = 4) const int MATERIAL_NDF = 0;
// 1 for the reference: an SG light's integral is then taken by Monte Carlo
// per sample; otherwise by the shading core's fixed quadrature.
layout(constant_id = 5) const int REFERENCE_MC = 0;
// An adaptive reference (a tolerance, not a fixed sample count): only its
// kernel holds the tile rule's barrier (tileConverged). llvmpipe runs every
// workgroup of a kernel with a barrier as coroutines, reached or not, which
// cost the fixed references and supersample-N about 11 % (docs/renderer.md).
layout(constant_id = 6) const int ADAPTIVE = 0;
// The renderer defines SHIMMER_SG_LIGHT for scenes lit by a spherical
// Gaussian; every other kernel leaves the SG integral out (pixel.glsl).
#ifndef SHIMMER_SG_LIGHT
#define SHIMMER_DELTA_LIGHTS_ONLY
#endif
#define SHIMMER_SCENE_FEATURES

struct CameraGpu {
  vec4 posTan;      // position, tan(fov_y / 2)
  vec4 fwdAspect;   // forward, width / height
  vec4 right;
  vec4 up;
};

// A uniform buffer: every invocation reads it at fixed addresses, which lavapipe
// turns into one scalar load (a storage-buffer load goes lane by lane).
layout(std140, binding = 0) uniform FrameBuf {
  CameraGpu cam;
  CameraGpu prevCam;
  vec4 lightA;  // direction or centre, type
  vec4 lightB;  // radiance or intensity, radius
  vec4 matA;    // alpha x, alpha y, glint alpha_l, glint density (the NDF is MATERIAL_NDF)
  vec4 matF0;
  vec4 matAlbedo;
  ivec4 size;   // width, height, first row and row count of this dispatch's band
} frame;
layout(std430, binding = 1) readonly buffer SceneBuf { vec4 words[]; } scene;
layout(std430, binding = 2) buffer ImageBuf { float values[]; } image;  // planar channels
layout(std430, binding = 3) buffer CounterBuf { uint unconverged; } counter;
// Per 8x8 tile (a workgroup), this frame: its list's first word and count,
// then the lists of BVH nodes (leaves) whose boxes reach the tile's camera
// rays (tile_lists.cpp); a count of -1 walks the BVH instead.
layout(std430, binding = 4) readonly buffer TileBuf { int words[]; } tiles;

layout(push_constant) uniform Push {
  vec4 params;   // the variant parameters' first four slots (VARIANT_PARAMS_FROM_SLOTS)
  ivec4 round;   // reference round, frame index, replicates K, seed (uint bits)
  vec4 target;   // relative standard error target (0: off), luminance floor
  vec4 params2;  // and their last four
} pc;

vec4 sceneWord(int i) { return scene.words[i]; }

#include "core.glsl"

#ifdef SHIMMER_USER_VARIANT
// struct UserParams and userParams(VariantParams), generated from the
// file's shimmer-param lines (user_variant.cpp).
#include "user_params.glsl"
#include "user_variant.glsl"
FilteredNdf runVariant(int ndf, vec2 alpha, ShadingFootprint f, VariantParams p) {
  return userVariant(ndf, alpha, f, userParams(p));
}
#else
FilteredNdf runVariant(int ndf, vec2 alpha, ShadingFootprint f, VariantParams p) {
  return evalVariant(VARIANT_ID, ndf, alpha, f, p);
}
#endif

FilteredNdf variantAt(int variant, int ndf, vec2 alpha, ShadingFootprint f, VariantParams p) {
  return runVariant(ndf, alpha, f, p);
}

#include "channels.glsl"

// ---- tile lists ---------------------------------------------------------------
// A pixel's primary ray tests its tile's listed leaves instead of walking
// the BVH: the workgroup's invocations read one list, in one order, so a
// SIMD batch runs as many steps as the list is long, where each lane's own
// walk ran as many as its longest lane's. The leaves come in the walk's
// order and take the walk's own per-leaf step, and every leaf a ray of the
// tile can reach is listed, so the hit is traceScene's.

int tileIndex() {
  int tilesX = (frame.size.x + 7) / 8;
  return ((int(gl_WorkGroupID.y) * 8 + frame.size.z) / 8) * tilesX + int(gl_WorkGroupID.x);
}

Hit traceTile(vec3 o, vec3 d) {
  int tile = tileIndex();
  int first = tiles.words[2 * tile];
  int count = tiles.words[2 * tile + 1];
  if (count < 0) return traceScene(o, d);
  Hit hit = unboundedHit(o, d);
  vec3 invD = inverseDirection(d);
  for (int i = 0; i < count; i++) {
    int node = tiles.words[first + i];
    vec4 n0 = sceneWord(1 + 2 * node);
    vec4 n1 = sceneWord(2 + 2 * node);
    hit = withLeafHit(hit, o, d, n1, nodeEntered(o, invD, n0, n1, hit.t));
  }
  return hit;
}

// pixelCandidates over the tile's list.
PixelCandidates tileCandidates(PixelCone k) {
  int tile = tileIndex();
  int first = tiles.words[2 * tile];
  int count = tiles.words[2 * tile + 1];
  if (count < 0) return pixelCandidates(k);
  PixelCandidates l = unboundedCandidates();
  for (int i = 0; i < count; i++) {
    int node = tiles.words[first + i];
    vec4 n0 = sceneWord(1 + 2 * node);
    vec4 n1 = sceneWord(2 + 2 * node);
    l = withLeafCandidate(l, k, n1, coneReachesNode(k, n0, n1));
  }
  return withLoadedPrims(l);
}

Camera loadCamera(CameraGpu g) {
  Camera c;
  c.pos = g.posTan.xyz;
  c.tanHalfFovY = g.posTan.w;
  c.fwd = g.fwdAspect.xyz;
  c.aspect = g.fwdAspect.w;
  c.right = g.right.xyz;
  c.up = g.up.xyz;
  c.size = vec2(frame.size.xy);
  return c;
}

// The image buffer holds one band of rows (the whole image when it fits the
// device's storage-buffer range), channel planes of width x band rows.
int planeSize() { return frame.size.x * frame.size.w; }
void put(int ch, int idx, float v) { image.values[ch * planeSize() + idx] = v; }
float get(int ch, int idx) { return image.values[ch * planeSize() + idx]; }
void put3(int ch, int idx, vec3 v) { put(ch, idx, v.x); put(ch + 1, idx, v.y); put(ch + 2, idx, v.z); }
vec3 get3(int ch, int idx) { return vec3(get(ch, idx), get(ch + 1, idx), get(ch + 2, idx)); }
float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// The normal-map filter of VARIANT_ID (normal_map.glsl), NMF_NONE for most.
const int NM_FILTER = VARIANT_ID / NMF_STRIDE;

// What a quad neighbour shares: the fields quadFootprint differences, and for
// a normal-map filter the uv of the texture footprint and the point, where
// the filtered normal is read again.
SurfaceSample partialSample(int prim, vec2 hpp, vec3 n, vec3 ng, vec2 uv, vec3 p) {
  SurfaceSample s = missedSample();
  s.prim = prim;
  s.hpp = hpp;
  s.n = n;
  s.ng = ng;
  s.uv = uv;
  s.p = p;
  return s;
}

SurfaceSample swapHorizontal(SurfaceSample s) {
  return partialSample(subgroupQuadSwapHorizontal(s.prim), subgroupQuadSwapHorizontal(s.hpp),
                       subgroupQuadSwapHorizontal(s.n), subgroupQuadSwapHorizontal(s.ng),
                       subgroupQuadSwapHorizontal(s.uv), subgroupQuadSwapHorizontal(s.p));
}
SurfaceSample swapVertical(SurfaceSample s) {
  return partialSample(subgroupQuadSwapVertical(s.prim), subgroupQuadSwapVertical(s.hpp),
                       subgroupQuadSwapVertical(s.n), subgroupQuadSwapVertical(s.ng),
                       subgroupQuadSwapVertical(s.uv), subgroupQuadSwapVertical(s.p));
}
// subgroupQuadBroadcast needs a constant lane, hence a macro.
#define broadcastLane(s, L)                                                                                   \
  partialSample(subgroupQuadBroadcast(s.prim, L), subgroupQuadBroadcast(s.hpp, L), subgroupQuadBroadcast(s.n, L), \
                subgroupQuadBroadcast(s.ng, L), subgroupQuadBroadcast(s.uv, L), subgroupQuadBroadcast(s.p, L))

void writeAovs(int idx, ivec2 px, SurfaceSample s, PixelShade sh, Camera prev) {
  vec2 motion = vec2(0.0);
  if (s.prim >= 0) motion = projectToPixel(prev, s.p) - pixelCentre(px);
  put(CH_MOTION, idx, motion.x);
  put(CH_MOTION + 1, idx, motion.y);
  put(CH_DEPTH, idx, s.t);
  put3(CH_NORMAL, idx, s.n);
  put(CH_ROUGHNESS, idx, sqrt(sh.alphaEff.x * sh.alphaEff.y));
  put(CH_FOOTPRINT, idx, sh.footprint.x);
  put(CH_FOOTPRINT + 1, idx, sh.footprint.y);
}

uint pcgHash(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

// The pixel's seed for this round; each sample hashes it with its index. A
// non-zero render seed gives the same frame independent randomness; seed 0
// keeps the sequences of renders made before it existed.
uint pixelSeed(ivec2 px) {
  uint frameKey = uint(pc.round.y);
  if (pc.round.w != 0) frameKey = pcgHash(frameKey ^ pcgHash(uint(pc.round.w)));
  return pcgHash(uint(px.x) + pcgHash(uint(px.y) + pcgHash(uint(pc.round.x) + pcgHash(frameKey))));
}

vec2 sampleJitter(uint seed, int s) {
  uint h = pcgHash(seed + uint(s) * 2654435769u);
  uint h2 = pcgHash(h);
  return vec2(float(h >> 8), float(h2 >> 8)) * (1.0 / 16777216.0);
}

// Sample k of the pixel: N x N jittered strata (box filter).
Ray sampleRay(Camera c, ivec2 px, uint seed, int k) {
  int j = k / SPP_N;
  int i = k - j * SPP_N;
  return cameraRay(c, vec2(px) + (vec2(i, j) + sampleJitter(seed, k)) / float(SPP_N));
}

// Running radiance sums of one pixel's samples in this round.
struct SampleSums {
  vec3 spec;
  vec3 diff;
};

const vec4 QUADRATURE = vec4(-1.0, 0.0, 0.0, 0.0);  // shadeSample: no random numbers

// Random numbers of sample k for an SG light's Monte Carlo integral (the
// reference): a 2D point for each strategy. Like the pixel positions, each
// replicate's N x N points of a strategy are stratified, one per cell of an
// N x N grid: the cells are dealt by k -> (k p + offset) mod N^2 (p a prime
// above 64, so a bijection for every N), the offset random per pixel and
// round, the point jittered in its cell. Each point is then uniform on its own
// (the estimate stays unbiased and the replicates independent), and the set
// covers the light as evenly as the pixel: on smooth highlights the
// reference's noise falls like N^-2 per axis pair instead of N^-1.
vec2 stratifiedPoint(uint seed, int k, uint prime) {
  uint cells = uint(SPP_N * SPP_N);
  uint cell = (uint(k) * prime + pcgHash(seed) % cells) % cells;
  vec2 jitter = sampleJitter(pcgHash(seed ^ prime), k);
  return (vec2(float(cell % uint(SPP_N)), float(cell / uint(SPP_N))) + jitter) / float(SPP_N);
}

vec4 lightNumbers(uint seed, int k) {
  if (REFERENCE_MC == 0) return QUADRATURE;
  vec2 a = stratifiedPoint(pcgHash(seed ^ 0x9e3779b9u), k, 65537u);
  vec2 b = stratifiedPoint(pcgHash(seed ^ 0x85ebca6bu), k, 257u);
  return vec4(a, b);
}

// A reference sample's NDF: a glint material at its finest level at the
// sample's point (glints.glsl), else the variant's.
FilteredNdf sampleNdf(SurfaceSample s, ShadingFootprint f, Material m, VariantParams vp) {
  if (MATERIAL_NDF == NDF_GLINTS) return glintNdfOf(VARIANT_ID, m, s, pointGlintFootprint(s));
  return runVariant(m.ndf, m.alpha, f, vp);
}

SampleSums addSample(SampleSums a, SurfaceSample s, Ray ray, Light light, Material m, VariantParams vp, vec4 u) {
  if ((SCENE_FEATURES & SCENE_ROUGHNESS_MAPS) != 0) m = materialAt(m, s);
  ShadingFootprint f = zeroFootprint(s);
#ifdef SHIMMER_USER_VARIANT
  f = analyticFootprint(s, ray, light);
#else
  if (VARIANT_ID != VARIANT_NONE) f = analyticFootprint(s, ray, light);
#endif
  PixelShade sh = shadeSample(s, f, sampleNdf(s, f, m, vp), m, light, VARIANT_ID, vp, u);
  a.spec += sh.specular;
  a.diff += sh.diffuse;
  return a;
}

// Where this invocation sits: its pixel and its lane in the 2x2 quad.
struct PixelLane {
  ivec2 px;
  uint lane;
};

PixelLane pixelLane() {
  uint lin = gl_SubgroupID * gl_SubgroupSize + gl_SubgroupInvocationID;
  uint quad = lin >> 2u;
  uint lane = lin & 3u;
  // Bands start on multiples of 8 rows, so a pixel's quad and workgroup lanes
  // are the same as in one dispatch over the whole image.
  ivec2 px = ivec2(gl_WorkGroupID.xy) * 8 + ivec2(0, frame.size.z) +
             ivec2(int((quad & 3u) * 2u + (lane & 1u)), int((quad >> 2u) * 2u + (lane >> 1u)));
  return PixelLane(px, lane);
}

Light frameLight() {
  Light light;
  light.type = int(frame.lightA.w);
  light.vec = frame.lightA.xyz;
  light.radiance = frame.lightB.xyz;
  light.radius = frame.lightB.w;
  return light;
}

Material frameMaterial() {
  Material m;
  m.ndf = MATERIAL_NDF;
  m.alpha = frame.matA.xy;
  m.f0 = frame.matF0.xyz;
  m.albedo = frame.matAlbedo.xyz;
  m.glintAlphaL = frame.matA.z;
  m.glintDensity = frame.matA.w;
  return m;
}

// The filter variants: one sample at the pixel centre, its footprint from
// the derivative source. Pixels past the image edge still run: they are the
// quad's helper lanes.
void shadePixelCentre(PixelLane pl, bool inside, int idx, Camera c, Camera prev, Light light, Material m,
                      VariantParams vp) {
  ivec2 px = pl.px;
  uint lane = pl.lane;
  Ray ray = cameraRay(c, pixelCentre(px));
  SurfaceSample s = surfaceOfHit(traceTile(ray.o, ray.d), ray, light);
  if ((SCENE_FEATURES & SCENE_ROUGHNESS_MAPS) != 0) m = materialAt(m, s);
  ShadingFootprint f;
  // A normal-map filter reads the map with the pixel's uv footprint and
  // differences the normals it filtered (renderPixelOracle in pixel.glsl).
  NormalMapFilter nf = levelZeroFilter();
  FilteredCentre fc;
  // A glint material's texture-space footprint (glints.glsl).
  GlintFootprint gf;
  if (DERIV_MODE == DERIV_ANALYTIC) {
    if (NM_FILTER != NMF_NONE) {
      nf = analyticNormalMapFilter(NM_FILTER, s, ray);
      fc = filteredCentre(s, c.pos, light, nf, m.alpha, vp.nm_scale);
      s = fc.s;
    }
    f = analyticFootprintFiltered(s, ray, light, nf);
    if (MATERIAL_NDF == NDF_GLINTS) gf = analyticGlintFootprint(s, ray);
  } else if (DERIV_MODE == DERIV_QUAD_FINE) {
    bool right = (lane & 1u) != 0u;
    bool bottom = (lane & 2u) != 0u;
    SurfaceSample h = quadNeighbour(s, swapHorizontal(s), c, light, px + ivec2(right ? -1 : 1, 0));
    SurfaceSample v = quadNeighbour(s, swapVertical(s), c, light, px + ivec2(0, bottom ? -1 : 1));
    if (NM_FILTER != NMF_NONE) {
      nf = quadNormalMapFilter(NM_FILTER, s, right ? h : s, right ? s : h, bottom ? v : s, bottom ? s : v);
      fc = filteredCentre(s, c.pos, light, nf, m.alpha, vp.nm_scale);
      s = fc.s;
      h = filteredSample(h, c.pos, light, nf);
      v = filteredSample(v, c.pos, light, nf);
    }
    f = quadFootprint(s, right ? h : s, right ? s : h, bottom ? v : s, bottom ? s : v);
    if (MATERIAL_NDF == NDF_GLINTS)
      gf = quadGlintFootprint(s, right ? h : s, right ? s : h, bottom ? v : s, bottom ? s : v);
  } else {
    ivec2 q = px - ivec2(int(lane & 1u), int(lane >> 1u));
    SurfaceSample s0 = quadNeighbour(s, broadcastLane(s, 0u), c, light, q);
    SurfaceSample s1 = quadNeighbour(s, broadcastLane(s, 1u), c, light, q + ivec2(1, 0));
    SurfaceSample s2 = quadNeighbour(s, broadcastLane(s, 2u), c, light, q + ivec2(0, 1));
    if (NM_FILTER != NMF_NONE) {
      nf = quadNormalMapFilter(NM_FILTER, s, s0, s1, s0, s2);
      fc = filteredCentre(s, c.pos, light, nf, m.alpha, vp.nm_scale);
      s = fc.s;
      s0 = filteredSample(s0, c.pos, light, nf);
      s1 = filteredSample(s1, c.pos, light, nf);
      s2 = filteredSample(s2, c.pos, light, nf);
    }
    f = quadFootprint(s, s0, s1, s0, s2);
    if (MATERIAL_NDF == NDF_GLINTS) gf = quadGlintFootprint(s, s0, s1, s0, s2);
  }
  if (NM_FILTER != NMF_NONE) {
    m.alpha = fc.lobe.alpha;
    s = turnedSample(s, fc.lobe.angle);
    f = turnedFootprint(f, fc.lobe.angle);
  }
  FilteredNdf ndf;
  if (MATERIAL_NDF == NDF_GLINTS) {
#ifdef SHIMMER_COUNTED_GLINTS
    // glints-points lights each microdetail at its own half vector.
    gf.dhppdx = f.dhpp_dx;
    gf.dhppdy = f.dhpp_dy;
#endif
    ndf = glintNdfOf(VARIANT_ID, m, s, gf);
  } else {
    ndf = runVariant(m.ndf, m.alpha, f, vp);
  }
  PixelShade sh = shadeSample(s, f, ndf, m, light, VARIANT_ID, vp, QUADRATURE);
  if (!inside) return;
  put3(CH_BEAUTY, idx, sh.specular + sh.diffuse);
  put3(CH_SPECULAR, idx, sh.specular);
  put3(CH_DIFFUSE, idx, sh.diffuse);
  put(CH_STDERR, idx, 0.0);
  put(CH_COUNT, idx, 1.0);
  put(CH_M2, idx, 0.0);
  writeAovs(idx, px, s, sh, prev);
}

// One replicate's N x N samples of the pixel. Two loops rather than one with
// a branch inside: lavapipe runs both sides of a branch for every sample,
// while a loop whose lanes are all done costs one pass. Almost every pixel
// has few candidates.
SampleSums replicateSums(ivec2 px, Camera c, Light light, Material m, VariantParams vp) {
  const int samples = SPP_N * SPP_N;
  PixelCandidates candidates = tileCandidates(pixelCone(c, px));
  bool fewCandidates = candidates.count <= PIXEL_CANDIDATES;
  const uint seed = pixelSeed(px);
  SampleSums sums = SampleSums(vec3(0.0), vec3(0.0));
  // Samples in pairs: two independent traces in one iteration give LLVM work
  // to interleave (the reference measured 12 % faster; fours were no better).
  int k = 0;
  for (; k + 1 < (fewCandidates ? samples : 0); k += 2) {
    Ray ray0 = sampleRay(c, px, seed, k);
    Ray ray1 = sampleRay(c, px, seed, k + 1);
    SurfaceSample s0 = tracePixelRay(candidates, ray0, light);
    SurfaceSample s1 = tracePixelRay(candidates, ray1, light);
    sums = addSample(sums, s0, ray0, light, m, vp, lightNumbers(seed, k));
    sums = addSample(sums, s1, ray1, light, m, vp, lightNumbers(seed, k + 1));
  }
  for (; k < (fewCandidates ? samples : 0); k++) {  // odd N x N
    Ray ray = sampleRay(c, px, seed, k);
    sums = addSample(sums, tracePixelRay(candidates, ray, light), ray, light, m, vp, lightNumbers(seed, k));
  }
  for (int k = 0; k < (fewCandidates ? 0 : samples); k++) {
    Ray ray = sampleRay(c, px, seed, k);
    sums = addSample(sums, traceRay(ray, light), ray, light, m, vp, lightNumbers(seed, k));
  }
  return sums;
}

// Adaptive references stop a whole 8x8 tile at once: a pixel samples on
// while any pixel of its workgroup is above the tolerance. A pixel's own
// replicates cannot tell a highlight far smaller than a sample's stratum
// from darkness (all K replicates miss it: stderr 0); stopping on that spread
// alone left sparse highlights dark and the frame's energy biased low
// (GpuReference.AdaptiveAgreesWithAFixedHighSppReferenceOnSparseHighlights).
// A neighbour that does see the highlight keeps the tile sampling until the
// highlight's pixels have all agreed. Each pixel reads only its own planes
// (written in the previous round), so the decision is free of races and the
// same on every device.
shared uint tileBusy;

bool tileConverged(bool pixelDone) {
  if (gl_LocalInvocationIndex == 0u) tileBusy = 0u;
  barrier();
  if (!pixelDone) atomicOr(tileBusy, 1u);
  barrier();
  return tileBusy == 0u;
}

// Supersampled: each round is one replicate, a full N x N jittered pattern
// (box filter) with its own jitter, merged into the running mean of earlier
// rounds. The standard error comes from the spread of the replicates' mean
// luminances (Welford over one observation per round): the i.i.d. formula
// over all samples ignores the stratification and overstates the error
// 2-27x. The count plane holds samples (replicates x N x N).
void addReferenceReplicate(ivec2 px, bool inside, int idx, Camera c, Camera prev, Light light, Material m,
                           VariantParams vp) {
  const int samples = SPP_N * SPP_N;
  float countA = !inside || pc.round.x == 0 ? 0.0 : get(CH_COUNT, idx);
  float repA = round(countA / float(samples));
  vec3 specA = repA > 0.0 ? get3(CH_SPECULAR, idx) : vec3(0.0);
  vec3 diffA = repA > 0.0 ? get3(CH_DIFFUSE, idx) : vec3(0.0);
  float m2A = repA > 0.0 ? get(CH_M2, idx) : 0.0;
  float meanYA = luminance(specA + diffA);
  // The spec constant alone as the condition: specialization folds it and
  // drops the branch, barriers and all (`ADAPTIVE != 0 && ...` would leave a
  // logical and of a constant that the specializer's passes keep).
  if (ADAPTIVE != 0) {
    if (pc.round.x > 0) {
      bool done = !inside;
      if (inside && repA >= float(pc.round.z))
        done = sqrt(m2A / ((repA - 1.0) * repA)) <= pc.target.x * max(meanYA, pc.target.y);
      if (tileConverged(done)) return;
    }
  }
  if (!inside) return;
  SampleSums sums = replicateSums(px, c, light, m, vp);
  vec3 specB = sums.spec / float(samples);
  vec3 diffB = sums.diff / float(samples);
  float rep = repA + 1.0;
  vec3 spec = specA + (specB - specA) / rep;
  vec3 diff = diffA + (diffB - diffA) / rep;
  float yB = luminance(specB + diffB);
  float m2All = m2A + (yB - meanYA) * (yB - luminance(spec + diff));
  float count = rep * float(samples);
  float se = rep > 1.0 ? sqrt(m2All / ((rep - 1.0) * rep)) : 0.0;
  put3(CH_BEAUTY, idx, spec + diff);
  put3(CH_SPECULAR, idx, spec);
  put3(CH_DIFFUSE, idx, diff);
  put(CH_COUNT, idx, count);
  put(CH_M2, idx, m2All);
  put(CH_STDERR, idx, se);
  if (pc.target.x > 0.0 && (rep < float(pc.round.z) || se > pc.target.x * max(luminance(spec + diff), pc.target.y)))
    atomicAdd(counter.unconverged, 1u);
  if (pc.round.x == 0) {
    // AOVs describe the pixel centre.
    Ray ray = cameraRay(c, pixelCentre(px));
    SurfaceSample s = traceRay(ray, light);
    ShadingFootprint f = analyticFootprint(s, ray, light);
    if ((SCENE_FEATURES & SCENE_ROUGHNESS_MAPS) != 0) m = materialAt(m, s);
    writeAovs(idx, px, s, shadeSample(s, f, sampleNdf(s, f, m, vp), m, light, VARIANT_ID, vp, QUADRATURE), prev);
  }
}

void main() {
  PixelLane pl = pixelLane();
  bool inside = pl.px.x < frame.size.x && pl.px.y < frame.size.y;
  int idx = (pl.px.y - frame.size.z) * frame.size.x + pl.px.x;
  Camera c = loadCamera(frame.cam);
  Camera prev = loadCamera(frame.prevCam);
  VariantParams vp;
  VARIANT_PARAMS_FROM_SLOTS(vp, pc.params, pc.params2);
  if (SPP_N == 1)
    shadePixelCentre(pl, inside, idx, c, prev, frameLight(), frameMaterial(), vp);
  else
    addReferenceReplicate(pl.px, inside, idx, c, prev, frameLight(), frameMaterial(), vp);
}
