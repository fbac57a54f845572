// Tangent-space normal maps and their filtering (seed 003_fd5f3d677171d779.txt,
// Hill, "Specular showdown in the wild west"): texel fetches from the scene
// words, bilinear / trilinear / anisotropic sampling of the mip chain the CPU
// built (renderer/scene/normal_map.cpp), and the normal-map filters, each of
// which turns the filtered statistics of the footprint into a shading normal
// and a roughness.
//
// Layout in the scene words (renderer/scene/scene.cpp packs it):
//   map header H          (levels, width0, height0, 0)
//   H + 1                 (scale u, scale v, 0, 0): texture repeats per uv unit
//   H + 2 + l             (first texel word of level l, width_l, height_l, 0)
//   texel (x, y) of a level, 3 words from first + 3 (y width + x):
//                         (E[n].xyz, Toksvig factor f_t), (B.xy, M.xx, M.yy), (M.xy, 0, 0, 0)
// n is the tangent-space normal, t = n.xy / n.z its slope (the slope space of
// hpp), B = E[t] and M = E[t t^T] LEAN's moments (Olano and Baker 2010, as
// cited in seed 003). Sides are powers of two, so wrapping is a bit mask.

// The includer provides `vec4 sceneWord(int i)` and defines SHIMMER_SCENE_WORDS;
// without it (stand-alone compile checks) the scene is empty.
#ifndef SHIMMER_SCENE_WORDS
vec4 sceneWord(int i) { return vec4(real(0), real(0), real(0), real(0)); }
#endif

// Normal-map filters (NMF_*): the part of a variant id above NMF_STRIDE,
// generated from shading/variant_table.json (variant_table.glsl).

// Hardware anisotropic filtering takes at most this many probes along the
// footprint's major axis (a common driver maximum is 16; 8 keeps the cost of
// a grazing pixel bounded on CPU drivers).
const int NORMAL_MAP_MAX_ANISO = 8;
// Seed 003: the Toksvig map is baked "with a fixed power [...] around 100".
const real TOKSVIG_FIXED_POWER = real(100);

struct NormalMapStats {
  vec3 meanN;  // E[n], unnormalised
  real ft;     // baked Toksvig factor at TOKSVIG_FIXED_POWER
  vec2 b;      // E[t]
  vec3 m;      // E[t.x^2], E[t.y^2], E[t.x t.y]
};

NormalMapStats zeroStats() {
  NormalMapStats s;
  s.meanN = vec3(real(0), real(0), real(0));
  s.ft = real(0);
  s.b = vec2(real(0), real(0));
  s.m = s.meanN;
  return s;
}

NormalMapStats addStats(NormalMapStats a, NormalMapStats b, real w) {
  a.meanN = a.meanN + b.meanN * w;
  a.ft = a.ft + b.ft * w;
  a.b = a.b + b.b * w;
  a.m = a.m + b.m * w;
  return a;
}

struct NormalMapLevel {
  int word;  // first texel word
  int w;
  int h;
};

int normalMapLevels(int header) { return int(sceneWord(header).x); }
vec2 normalMapScale(int header) {
  vec4 s = sceneWord(header + 1);
  return vec2(s.x, s.y);
}

NormalMapLevel normalMapLevel(int header, int level) {
  vec4 e = sceneWord(header + 2 + level);
  NormalMapLevel l;
  l.word = int(e.x);
  l.w = int(e.y);
  l.h = int(e.z);
  return l;
}

// Texel (x, y) with the map repeating (sides are powers of two).
NormalMapStats normalMapTexel(NormalMapLevel l, int x, int y) {
  int i = l.word + 3 * ((y & (l.h - 1)) * l.w + (x & (l.w - 1)));
  vec4 a = sceneWord(i);
  vec4 b = sceneWord(i + 1);
  vec4 c = sceneWord(i + 2);
  NormalMapStats s;
  s.meanN = vec3(a.x, a.y, a.z);
  s.ft = a.w;
  s.b = vec2(b.x, b.y);
  s.m = vec3(b.z, b.w, c.x);
  return s;
}

// Texel coordinates of uv at a level: texel centres at half-integers; the
// fractional part of uv first, so that far-away uv keep their precision.
vec2 normalMapTexelCoord(NormalMapLevel l, vec2 uv) {
  vec2 f = uv - floor(uv);
  return vec2(f.x * real(l.w), f.y * real(l.h)) - vec2(real(0.5), real(0.5));
}

NormalMapStats normalMapBilinear(NormalMapLevel l, vec2 uv) {
  vec2 c = normalMapTexelCoord(l, uv);
  vec2 c0 = floor(c);
  vec2 f = c - c0;
  int x = int(c0.x);
  int y = int(c0.y);
  NormalMapStats s = zeroStats();
  s = addStats(s, normalMapTexel(l, x, y), (real(1) - f.x) * (real(1) - f.y));
  s = addStats(s, normalMapTexel(l, x + 1, y), f.x * (real(1) - f.y));
  s = addStats(s, normalMapTexel(l, x, y + 1), (real(1) - f.x) * f.y);
  s = addStats(s, normalMapTexel(l, x + 1, y + 1), f.x * f.y);
  return s;
}

NormalMapStats normalMapNearest(NormalMapLevel l, vec2 uv) {
  vec2 c = floor(normalMapTexelCoord(l, uv) + vec2(real(0.5), real(0.5)));
  return normalMapTexel(l, int(c.x), int(c.y));
}

// The footprint's statistics as texture hardware filters them: the level
// from the footprint's minor axis (or its major axis over the probe count),
// up to NORMAL_MAP_MAX_ANISO trilinear probes spread over the major axis.
// duvdx, duvdy: the uv change across one pixel in x and y.
NormalMapStats normalMapFiltered(int header, vec2 uv, vec2 duvdx, vec2 duvdy) {
  int levels = normalMapLevels(header);
  NormalMapLevel l0 = normalMapLevel(header, 0);
  vec2 size = vec2(real(l0.w), real(l0.h));
  vec2 ax = duvdx * size;
  vec2 ay = duvdy * size;
  real lx = min(length(ax), real(1e8));
  real ly = min(length(ay), real(1e8));
  vec2 major = lx >= ly ? duvdx : duvdy;
  real lmaj = max(lx, ly);
  real lmin = max(min(lx, ly), real(1e-8));
  int probes = int(min(ceil(lmaj / lmin), real(NORMAL_MAP_MAX_ANISO)));
  probes = max(probes, 1);
  real lod = clamp(log(max(lmaj / real(probes), real(1e-8))) / log(real(2)), real(0), real(levels - 1));
  int la = int(floor(lod));
  int lb = min(la + 1, levels - 1);
  real fl = lod - real(la);
  NormalMapLevel A = normalMapLevel(header, la);
  NormalMapLevel B = normalMapLevel(header, lb);
  NormalMapStats s = zeroStats();
  real w = real(1) / real(probes);
  for (int i = 0; i < probes; i++) {
    vec2 at = uv + major * ((real(i) + real(0.5)) * w - real(0.5));
    s = addStats(s, normalMapBilinear(A, at), w * (real(1) - fl));
    if (fl > real(0)) s = addStats(s, normalMapBilinear(B, at), w * fl);
  }
  return s;
}

// The filter a pixel applies and its uv footprint (uv change across one
// pixel in x and y, before the map's scale).
struct NormalMapFilter {
  int mode;  // NMF_*
  vec2 duvdx;
  vec2 duvdy;
};

NormalMapFilter levelZeroFilter() {
  NormalMapFilter f;
  f.mode = NMF_NONE;
  f.duvdx = vec2(real(0), real(0));
  f.duvdy = f.duvdx;
  return f;
}

// What a normal-map filter reads at a pixel: NMF_NONE and NMF_POINT read level
// 0, the others the filtered chain.
NormalMapStats normalMapStats(int header, NormalMapFilter f, vec2 uv) {
  vec2 sc = normalMapScale(header);
  vec2 st = uv * sc;
  NormalMapLevel l0 = normalMapLevel(header, 0);
  if (f.mode == NMF_NONE) return normalMapBilinear(l0, st);
  if (f.mode == NMF_POINT) return normalMapNearest(l0, st);
  return normalMapFiltered(header, st, f.duvdx * sc, f.duvdy * sc);
}

// The tangent-space shading normal a filter uses: the (bilinear or filtered)
// mean normal renormalised, or for LEAN and CLEAN the normal of the mean
// slope B.
vec3 normalMapNormal(int mode, NormalMapStats s) {
  vec3 up = vec3(real(0), real(0), real(1));
  if (mode == NMF_LEAN || mode == NMF_CLEAN) return safeNormalize(vec3(s.b.x, s.b.y, real(1)), up);
  return safeNormalize(s.meanN, up);
}

// |E[n]| in (0, 1): 1 - |Na| cancels where the normals agree, so it is taken
// from the length, and kept a hair below 1 for the divisions below.
real meanNormalLength(NormalMapStats s) { return clamp(length(s.meanN), real(1e-6), real(1) - real(1e-7)); }

// Blinn-Phong power <-> Beckmann roughness, alpha^2 = 2 / (s + 2) (Walter et
// al. 2007), the conversion under which seed 003's power remaps act on alpha.
real blinnPhongPower(real alpha2) { return max(real(2) / max(alpha2, real(1e-8)) - real(2), real(0)); }
real alpha2OfPower(real power) { return real(2) / (max(power, real(0)) + real(2)); }

// The material roughness alpha (per tangent axis) widened by the normal
// variance inside the footprint. Widening adds slope variances: a Beckmann
// lobe of roughness a has slope variance a^2 / 2 per axis, so a footprint
// slope variance sigma^2 adds 2 sigma^2 to alpha^2 (seed 003: p = s / (1 + s
// sigma^2) is the same statement on the Blinn-Phong power). Engines combine
// a normal-map filter with a geometric one the same way: the geometric filter
// widens the roughness this returns.
vec2 normalMapAlphaOf(int mode, NormalMapStats s, vec2 alpha) {
  vec2 a2 = alpha * alpha;
  vec2 one = vec2(real(1), real(1));
  if (mode == NMF_TOKSVIG) {
    // Seed 003: sigma^2 = (1 - |Na|) / |Na|, in its GGX / Beckmann alpha form.
    real r = meanNormalLength(s);
    real sigma2 = (real(1) - r) / r;
    return sqrt(min(a2 + vec2(real(2) * sigma2, real(2) * sigma2), max(a2, one)));
  }
  if (mode == NMF_TOKSVIG_BP || mode == NMF_TOKSVIG_MAP) {
    // Seed 003: f_t = |Na| / (|Na| + s (1 - |Na|)), power f_t s; the baked
    // map holds f_t at the fixed power and converts with
    // ft /= lerp(s / fixed_s, 1, ft). Per axis, on the power of that axis.
    vec2 o;
    for (int i = 0; i < 2; i++) {
      real p = blinnPhongPower(i == 0 ? a2.x : a2.y);
      real ft;
      if (mode == NMF_TOKSVIG_BP) {
        real r = meanNormalLength(s);
        ft = r / (r + p * (real(1) - r));
      } else {
        real fixedFt = clamp(s.ft, real(1e-6), real(1));
        real k = p / TOKSVIG_FIXED_POWER;
        ft = fixedFt / (k + (real(1) - k) * fixedFt);
      }
      real w = sqrt(max(alpha2OfPower(ft * p), i == 0 ? a2.x : a2.y));
      if (i == 0) o.x = w;
      else o.y = w;
    }
    return o;
  }
  if (mode == NMF_LEAN || mode == NMF_CLEAN) {
    // LEAN: Sigma = M - B B^T; its diagonal here, the whole matrix in
    // normalMapLobe. CLEAN (seed 003: sigma^2 = M_z - (M_x^2 + M_y^2), M_z
    // the mean squared slope) is read per axis, (E|t|^2 - |B|^2) / 2, so that
    // it equals LEAN and Toksvig on isotropic bumps.
    vec2 var = vec2(max(s.m.x - s.b.x * s.b.x, real(0)), max(s.m.y - s.b.y * s.b.y, real(0)));
    if (mode == NMF_CLEAN) {
      real v = (var.x + var.y) * real(0.5);
      var = vec2(v, v);
    }
    return sqrt(min(a2 + real(2) * var, max(a2, one)));
  }
  if (mode == NMF_VMF || mode == NMF_HDRP) {
    // von Mises-Fisher fit (Banerjee et al. 2005, as used by Han et al.
    // 2007): kappa = (3 r - r^3) / (1 - r^2); Han: alpha^2 += 2 / kappa.
    // HDRP (TextureNormalVariance): variance 0.25 / kappa, alpha^2 += 2
    // variance, the variance capped at 0.03125.
    real r = meanNormalLength(s);
    real invKappa = (real(1) - r * r) / (real(3) * r - r * r * r);
    real add = mode == NMF_VMF ? real(2) * invKappa : real(2) * min(real(0.25) * invKappa, real(0.03125));
    return sqrt(min(a2 + vec2(add, add), max(a2, one)));
  }
  return alpha;  // NMF_NONE, NMF_POINT, NMF_MIP
}

// The same with the added alpha^2 scaled by `scale` (the nm_scale parameter,
// which the fit tunes per material; 1 is each filter as published).
vec2 normalMapAlpha(int mode, NormalMapStats s, vec2 alpha, real scale) {
  vec2 a2 = alpha * alpha;
  vec2 w = normalMapAlphaOf(mode, s, alpha);
  vec2 one = vec2(real(1), real(1));
  return sqrt(min(a2 + (w * w - a2) * scale, max(a2, one)));
}

// A lobe whose axes are the tangent frame turned by `angle` (radians, from
// the tangent towards the bitangent), with roughness alpha along them.
struct NormalMapLobe {
  vec2 alpha;
  real angle;
};

// LEAN as published (Olano and Baker 2010): the slopes' covariance
// R = diag(alpha^2) + 2 scale Sigma, Sigma = M - B B^T with its off-diagonal
// term, so ridges at any angle to the tangent give a lobe stretched across
// them. R is symmetric 2x2: its eigenvectors are the lobe's axes and its
// eigenvalues the alpha^2 along them; the lobe's density is then the
// material NDF with those alphas in the turned frame, whose normalisation is
// 1 / (pi sqrt(det R)) = 1 / (2 pi sqrt(det(R / 2))), the published
// erratum's 1 / (2 pi sqrt(det Sigma)) for the Gaussian. Other filters keep
// the frame (angle 0).
NormalMapLobe normalMapLobe(int mode, NormalMapStats s, vec2 alpha, real scale) {
  NormalMapLobe l;
  l.angle = real(0);
  l.alpha = normalMapAlpha(mode, s, alpha, scale);
  if (mode != NMF_LEAN) return l;
  real sxx = max(s.m.x - s.b.x * s.b.x, real(0));
  real syy = max(s.m.y - s.b.y * s.b.y, real(0));
  real sxy = s.m.z - s.b.x * s.b.y;
  sxy = clamp(sxy, -sqrt(sxx * syy), sqrt(sxx * syy));  // Sigma stays positive semi-definite
  real rxx = alpha.x * alpha.x + real(2) * scale * sxx;
  real ryy = alpha.y * alpha.y + real(2) * scale * syy;
  real rxy = real(2) * scale * sxy;
  real mean = (rxx + ryy) * real(0.5);
  real dev = sqrt(sqr((rxx - ryy) * real(0.5)) + rxy * rxy);
  real cap = max(max(alpha.x * alpha.x, alpha.y * alpha.y), real(1));
  real major = sqrt(min(mean + dev, cap));
  real minor = sqrt(max(min(mean - dev, cap), real(0)));
  // The major axis' angle is in [-pi/2, pi/2]; the turn is kept within
  // +-pi/4 by naming whichever axis is nearer the tangent x, so that
  // neighbouring pixels' frames (and their hpp differences) stay continuous.
  real angle = real(0.5) * atan(real(2) * rxy, rxx - ryy);
  l.alpha = vec2(major, minor);
  if (angle > real(0.25) * PI) {
    angle = angle - HALF_PI;
    l.alpha = vec2(minor, major);
  } else if (angle < real(-0.25) * PI) {
    angle = angle + HALF_PI;
    l.alpha = vec2(minor, major);
  }
  l.angle = angle;
  return l;
}
