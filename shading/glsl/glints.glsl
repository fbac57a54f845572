// Glints: the biscale NDF of Zirr and Kaplanyan realised by a coherent
// stochastic process (seed 001_3f378f7234669c2f.txt, slides 11-15, "Materials
// with Specular Microdetails"; Zirr and Kaplanyan, "Real-time Rendering of
// Procedural Multiscale Materials", I3D 2016). docs/glints.md derives what
// follows; in short:
//
// - Microdetails: `density` per unit area of the surface, each with a slope
//   drawn from D_m (Beckmann, the material's alpha) and a local lobe D_l of
//   roughness alpha_l. The global NDF D_g = D_m * D_l is Beckmann with
//   alpha_g^2 = alpha^2 + alpha_l^2 (Gaussians in slope space add variances).
// - Space: power-of-two texture-space grids; a level-0 cell holds one
//   microdetail on average (its side is 1 / sqrt(density)), a level-L cell
//   4^L. The pixel footprint picks the level (trilinear) and, where it is
//   anisotropic, up to GLINT_MAX_ANISOTROPY probes along its long axis.
// - Slopes: a grid of bins of side w over the slope plane, shifted per
//   texture cell by a random offset (the slides' perturbed partition, so that
//   cells do not change all at once). The slides bin on a paraboloid map of
//   the half vector; shimmer bins in slope space, where a Beckmann bin's
//   probability is a product of two erfc differences, exact, and which is
//   the paraboloid map to first order (docs/glints.md).
// - Per cell and bin, one binomial draw k ~ B(n, p_bin), seeded by the 4D
//   index (level, cell, bin): the microdetails of the cell that reflect.
//   The cell's density at h is the bilinear blend over the 4 bins around h
//   of k / (n w^2). Bilinear in bins is a tent, the random offset a box:
//   averaged over cells the lobe of one microdetail has variance w^2 / 4,
//   which w = sqrt(2) alpha_l makes alpha_l^2 / 2, D_l's. The expectation
//   of the whole process is then D_m * (box * tent) ~ D_g.

const int GLINT_FILTERED = 0;  // glints-zk16: levels and probes from the pixel footprint
const int GLINT_POINT = 1;     // none: the finest level at the point (what the reference averages)
const int GLINT_NAIVE = 2;     // glints-naive: the level-0 cell holding the point, its nearest bin
const int GLINT_SMOOTH = 3;    // glints-smooth: D_g itself

// Seed 001, "Performance": maximum anisotropy 16x.
const int GLINT_MAX_ANISOTROPY = 16;
// 4^24 microdetails per cell (~3e14) is more than any footprint holds at a
// density a glint material would use; k / n stays representable in float.
const int GLINT_MAX_LEVEL = 24;
// Binomial draws with a mean above this use the normal approximation; below,
// exact inversion of the (real-n) binomial in at most GLINT_INVERSION_STEPS.
const real GLINT_INVERSION_MEAN = real(16);
const int GLINT_INVERSION_STEPS = 64;

struct GlintMaterial {
  vec2 alpha;     // D_m, the microdetail slopes (Beckmann)
  real alphaL;    // D_l, one microdetail's lobe
  real density;   // microdetails per unit area
};

// The footprint in world-scaled texture coordinates (pixel.glsl builds it):
// uv of the point, its change per pixel, and the surface area per unit uv
// area there (1 on planes).
struct GlintFootprint {
  vec2 uv;
  vec2 duvdx;
  vec2 duvdy;
  real areaScale;
};

vec2 glintGlobalAlpha(GlintMaterial g) {
  vec2 a = clampAlpha(g.alpha);
  real l = clamp(g.alphaL, ALPHA_MIN, ALPHA_MAX);
  return sqrt(a * a + vec2(l * l, l * l));
}

// PCG output permutation (O'Neill 2014), as the kernel's sample hash.
uint glintHash(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}

uint glintCellHash(int level, ivec2 cell) {
  return glintHash(uint(cell.y) ^ glintHash(uint(cell.x) ^ glintHash(uint(level) + 0x9e3779b9u)));
}

// The 4D index of the slides: texture cell and slope bin.
uint glintBinHash(uint cellHash, ivec2 bin) {
  return glintHash(uint(bin.y) ^ glintHash(uint(bin.x) ^ glintHash(cellHash ^ 0x85ebca6bu)));
}

// A uniform number in (0, 1), never 0 or 1.
real glintUniform(uint h) { return (real(h >> 8u) + real(0.5)) * real(1.0 / 16777216.0); }

// erfc with relative error below 1.2e-7 everywhere (Numerical Recipes'
// erfcc, Chebyshev fit): the tails stay accurate, which the bin
// probabilities far from the lobe need (n p there must not turn into
// spurious sparkles).
real glintErfc(real x) {
  real z = abs(x);
  real t = real(1) / (real(1) + real(0.5) * z);
  real poly =
      real(-1.26551223) +
      t * (real(1.00002368) +
           t * (real(0.37409196) +
                t * (real(0.09678418) +
                     t * (real(-0.18628806) +
                          t * (real(0.27886807) +
                               t * (real(-1.13520398) +
                                    t * (real(1.48851587) + t * (real(-0.82215223) + t * real(0.17087277)))))))));
  real r = t * exp(min(-z * z + poly, real(0)));
  return x >= real(0) ? r : real(2) - r;
}

// P(a <= X <= b) for X with Beckmann's slope marginal exp(-x^2 / alpha^2) /
// (sqrt(pi) alpha), formed from the tail nearer the bin so that it does not
// cancel.
real glintInterval(real a, real b, real alpha) {
  real ea = a / alpha;
  real eb = b / alpha;
  if (ea >= real(0)) return max(real(0.5) * (glintErfc(ea) - glintErfc(eb)), real(0));
  if (eb <= real(0)) return max(real(0.5) * (glintErfc(-eb) - glintErfc(-ea)), real(0));
  return max(real(1) - real(0.5) * (glintErfc(-ea) + glintErfc(eb)), real(0));
}

// Standard normal quantile of u in (0, 1): sqrt(2) erfinv(2u - 1), Giles'
// single-precision erfinv ("Approximating the erfinv function", 2010), with
// 1 - x^2 = 4 u (1 - u) formed without cancellation.
real glintNormalQuantile(real u) {
  real x = real(2) * u - real(1);
  real w = -log(real(4) * u * (real(1) - u));
  real p;
  if (w < real(5)) {
    w = w - real(2.5);
    p = real(2.81022636e-08);
    p = real(3.43273939e-07) + p * w;
    p = real(-3.5233877e-06) + p * w;
    p = real(-4.39150654e-06) + p * w;
    p = real(0.00021858087) + p * w;
    p = real(-0.00125372503) + p * w;
    p = real(-0.00417768164) + p * w;
    p = real(0.246640727) + p * w;
    p = real(1.50140941) + p * w;
  } else {
    w = sqrt(w) - real(3);
    p = real(-0.000200214257);
    p = real(0.000100950558) + p * w;
    p = real(0.00134934322) + p * w;
    p = real(-0.00367342844) + p * w;
    p = real(0.00573950773) + p * w;
    p = real(-0.0076224613) + p * w;
    p = real(0.00943887047) + p * w;
    p = real(1.00167406) + p * w;
    p = real(2.83297682) + p * w;
  }
  return real(1.41421356237309505) * p * x;
}

// log(1 - p) for p in [0, 1) without losing small p to rounding.
real glintLog1m(real p) {
  if (p < real(1e-3)) return -p * (real(1) + p * (real(0.5) + p / real(3)));
  return log(real(1) - p);
}

// Inversion of Binomial(n, p) at u for an integer n >= 0: P(k) = P(k-1)
// (n - k + 1) / k p / (1 - p) from P(0) = (1 - p)^n, for a small mean.
real glintBinomialInversion(real n, real p, real u) {
  real mean = n * p;
  real pk = exp(n * glintLog1m(p));
  real cdf = pk;
  real ratio = p / (real(1) - p);
  real k = real(0);
  for (int i = 0; i < GLINT_INVERSION_STEPS; i++) {
    if (u <= cdf) break;
    real next = pk * (n - k) / (k + real(1)) * ratio;
    // Past n, or where the rest of the tail is below float's resolution of
    // cdf: u lies in a tail float cannot tell apart.
    if (!(next > real(0)) || (k > mean && next < real(1e-8))) break;
    pk = next;
    k += real(1);
    cdf += pk;
  }
  return k;
}

// One draw of the microdetails of a cell that reflect: the cell holds a
// real n of them in expectation (density times area), so floor(n) or
// floor(n) + 1 with the uniform u2 (mean n), and each reflects with
// probability p: k ~ Binomial(N, p), E k = n p. Monotone in u: inversion
// where the mean (or the failures' mean N (1 - p)) is small, the sparse,
// sparkling regime; else the normal approximation with the binomial's
// variance, whose clamps to [0, N] then sit 4 standard deviations away and
// so keep the mean.
real glintBinomial(real n, real p, real u, real u2) {
  if (!(n > real(0)) || !(p > real(0))) return real(0);
  real count = floor(n);
  if (u2 < n - count) count += real(1);
  if (count == real(0)) return real(0);
  if (p >= real(1)) return count;
  real mean = count * p;
  if (mean <= GLINT_INVERSION_MEAN) return glintBinomialInversion(count, p, u);
  if (count - mean <= GLINT_INVERSION_MEAN) return count - glintBinomialInversion(count, real(1) - p, real(1) - u);
  return clamp(mean + sqrt(mean * (real(1) - p)) * glintNormalQuantile(u), real(0), count);
}

// The draw of the 4D index (cell, bin): two uniforms from its hash.
real glintDraw(real n, real p, uint h) { return glintBinomial(n, p, glintUniform(h), glintUniform(glintHash(h ^ 0x27d4eb2fu))); }

// The slope density the microdetails of one cell give at hpp: n of them
// (expected), bins of side w shifted by the cell's own offset. `blend`:
// bilinear over the 4 bins around hpp; else the bin holding hpp.
real glintCellDensity(GlintMaterial g, int level, ivec2 cell, vec2 hpp, real n, real w, bool blend) {
  if (!(n > real(1e-6))) return real(0);
  vec2 a = clampAlpha(g.alpha);
  uint ch = glintCellHash(level, cell);
  vec2 offset = vec2(glintUniform(ch), glintUniform(glintHash(ch)));
  vec2 t = hpp / w - offset;  // bin b spans t in [b, b + 1)
  if (!blend) {
    vec2 b = floor(t);
    real px = glintInterval((b.x + offset.x) * w, (b.x + offset.x + real(1)) * w, a.x);
    real py = glintInterval((b.y + offset.y) * w, (b.y + offset.y + real(1)) * w, a.y);
    real k = glintDraw(n, px * py, glintBinHash(ch, ivec2(b)));
    return k / (n * w * w);
  }
  t = t - vec2(real(0.5), real(0.5));  // bin b's centre at t = b
  vec2 b0 = floor(t);
  vec2 f = t - b0;
  vec2 e0 = (b0 + offset) * w;  // lower edges of the first bins
  real px0 = glintInterval(e0.x, e0.x + w, a.x);
  real px1 = glintInterval(e0.x + w, e0.x + real(2) * w, a.x);
  real py0 = glintInterval(e0.y, e0.y + w, a.y);
  real py1 = glintInterval(e0.y + w, e0.y + real(2) * w, a.y);
  ivec2 i0 = ivec2(b0);
  real k00 = glintDraw(n, px0 * py0, glintBinHash(ch, i0));
  real k10 = glintDraw(n, px1 * py0, glintBinHash(ch, i0 + ivec2(1, 0)));
  real k01 = glintDraw(n, px0 * py1, glintBinHash(ch, i0 + ivec2(0, 1)));
  real k11 = glintDraw(n, px1 * py1, glintBinHash(ch, i0 + ivec2(1, 1)));
  real k = mix(mix(k00, k10, f.x), mix(k01, k11, f.x), f.y);
  return k / (n * w * w);
}

// One level's density at texture point p (in level-0 cell units): bilinear
// over the 4 cells around p.
real glintLevelDensity(GlintMaterial g, int level, vec2 p, vec2 hpp, real areaScale, real w) {
  real size = exp2(real(level));
  real n = areaScale * size * size;
  vec2 q = p / size - vec2(real(0.5), real(0.5));
  vec2 c0 = floor(q);
  vec2 f = q - c0;
  ivec2 c = ivec2(c0);
  real d00 = glintCellDensity(g, level, c, hpp, n, w, true);
  real d10 = glintCellDensity(g, level, c + ivec2(1, 0), hpp, n, w, true);
  real d01 = glintCellDensity(g, level, c + ivec2(0, 1), hpp, n, w, true);
  real d11 = glintCellDensity(g, level, c + ivec2(1, 1), hpp, n, w, true);
  return mix(mix(d00, d10, f.x), mix(d01, d11, f.x), f.y);
}

// How the footprint is read: the level (real, trilinear), the probes along
// the long axis and their spacing, in level-0 cell units.
struct GlintLod {
  real level;
  int probes;
  vec2 step;
};

// The box pixel maps to the parallelogram spanned by dx and dy; its axes are
// those of dx dx^T + dy dy^T (lengths whose product is the area). The probes
// are sized by the short axis, at least a cell and at least 1/16 of the long
// axis, and cover the long one.
GlintLod glintLod(vec2 dx, vec2 dy) {
  real xx = dx.x * dx.x + dy.x * dy.x;
  real yy = dx.y * dx.y + dy.y * dy.y;
  real xy = dx.x * dx.y + dy.x * dy.y;
  real half_trace = real(0.5) * (xx + yy);
  real root = sqrt(sqr(real(0.5) * (xx - yy)) + xy * xy);
  real major = sqrt(half_trace + root);
  real area = abs(cross2(dx, dy));
  real minor = major > real(0) ? area / major : real(0);
  vec2 axis = vec2(real(1), real(0));
  if (root > real(0)) {
    // Eigenvector of the larger eigenvalue, from the row with more weight.
    vec2 e = xx >= yy ? vec2(half_trace + root - yy, xy) : vec2(xy, half_trace + root - xx);
    real len = length(e);
    if (len > real(0)) axis = e / len;
  }
  GlintLod o;
  real size = max(max(minor, major / real(GLINT_MAX_ANISOTROPY)), real(1));
  o.level = log2(size);
  o.probes = int(clamp(ceil(major / size - real(1e-3)), real(1), real(GLINT_MAX_ANISOTROPY)));
  o.step = axis * (major / real(o.probes));
  return o;
}

// Footprint components beyond 1e15 cells (or not finite) read as 1e15: the
// coarsest level already covers them, and their squares stay finite in float.
real glintFiniteComponent(real x) {
  if (!(abs(x) < real(1e15))) return real(1e15);
  return x;
}
vec2 glintFinite(vec2 v) { return vec2(glintFiniteComponent(v.x), glintFiniteComponent(v.y)); }

FilteredNdf glintNdf(int mode, GlintMaterial g, vec2 hpp, GlintFootprint fp) {
  FilteredNdf o;
  vec2 alphaG = glintGlobalAlpha(g);
  o.alpha_eff = alphaG;
  hpp = clampSlope(hpp);
  if (mode == GLINT_SMOOTH || !(g.density > real(0))) {
    o.slope_density = slopeDensity(NDF_BECKMANN, hpp, alphaG);
    o.density = o.slope_density * slopeToSolidAngle(hpp);
    return o;
  }
  real w = real(1.41421356237309505) * clamp(g.alphaL, ALPHA_MIN, ALPHA_MAX);
  real cell = inversesqrt(g.density);
  // Texture points beyond 1e9 cells would overflow the cell index.
  vec2 lim = vec2(real(1e9), real(1e9));
  vec2 p = clamp(fp.uv / cell, -lim, lim);
  if (!(p.x == p.x) || !(p.y == p.y)) p = vec2(real(0), real(0));
  real areaScale = max(fp.areaScale, real(1e-6));
  real d = real(0);
  if (mode == GLINT_NAIVE) {
    d = glintCellDensity(g, 0, ivec2(floor(p)), hpp, areaScale, w, false);
  } else if (mode == GLINT_POINT) {
    d = glintLevelDensity(g, 0, p, hpp, areaScale, w);
  } else {
    GlintLod lod = glintLod(glintFinite(fp.duvdx / cell), glintFinite(fp.duvdy / cell));
    real level = clamp(lod.level, real(0), real(GLINT_MAX_LEVEL));
    int l0 = min(int(floor(level)), GLINT_MAX_LEVEL - 1);
    real t = level - real(l0);
    SHIMMER_DONT_UNROLL
    for (int i = 0; i < lod.probes; i++) {
      vec2 q = p + lod.step * (real(i) + real(0.5) - real(0.5) * real(lod.probes));
      real lo = glintLevelDensity(g, l0, q, hpp, areaScale, w);
      real hi = t > real(0) ? glintLevelDensity(g, l0 + 1, q, hpp, areaScale, w) : real(0);
      d += mix(lo, hi, t);
    }
    d /= real(lod.probes);
  }
  o.slope_density = d;
  o.density = d * slopeToSolidAngle(hpp);
  return o;
}

// The glint mode a variant shades a glint material with (variants.glsl).
int glintModeOf(int variant) {
  int v = geometricVariant(variant);
  if (v == VARIANT_GLINTS_ZK16) return GLINT_FILTERED;
  if (v == VARIANT_GLINTS_NAIVE) return GLINT_NAIVE;
  if (v == VARIANT_GLINTS_SMOOTH) return GLINT_SMOOTH;
  return GLINT_POINT;
}
