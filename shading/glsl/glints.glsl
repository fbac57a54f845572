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
const int GLINT_COUNTING = 4;  // glints-zk16-counting: zk16's cells and bins, their weights distributing the count
const int GLINT_DB23 = 5;      // glints-db23: Deliot and Belcour's anisotropic grids, the count distributed
const int GLINT_POINTS = 6;    // glints-points: point microdetails in the footprint, each at its own half vector

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
  // The slope-space half vector's change per pixel (ShadingFootprint's
  // dhpp_dx, dhpp_dy): where in the footprint a microdetail lies decides the
  // half vector it reflects at (glints-points). Zero: one half vector.
  vec2 dhppdx;
  vec2 dhppdy;
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

// A cell of glints-db23's grid `grid` (a hash of its level, ratio and
// direction).
uint glintGridCellHash(uint grid, ivec2 cell) { return glintHash(uint(cell.y) ^ glintHash(uint(cell.x) ^ grid)); }

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

// ---- Counting the footprint's microdetails --------------------------------
// glints-zk16 blends independent draws linearly: over the 4 bins around h, the
// 4 cells around each probe, two levels and up to 16 probes (seed 001, slide
// 13: "one binomial draw per grid cell, trilinear interpolation"; slide 15:
// "maximum anisotropy 16x"). A blend sum_i w_i k_i of independent draws keeps
// the mean and multiplies the variance by sum_i w_i^2, well below 1: the
// published model's pixels are smoother than the binomial law of their
// microdetails. Deliot and Belcour ("Real-Time Rendering of Glinty
// Appearances using Distributed Binomial Laws on Anisotropic Grids", HPG
// 2023) keep the law with the counting their title names: the footprint's
// N microdetails are distributed among the draws by the blend's weights, draw
// i counting B(N w_i, p_i), and the count is the sum. Independent binomials
// of one p add to the binomial of the summed trials, so the count is B(N, p)
// whatever the weights. The weights that distribute are those of the cells,
// levels, grids and probes; the 4 slope bins around h keep their bilinear
// weights, which are each microdetail's lobe (glintCellCount). The inversion
// is monotone in n, so a weight that grows adds microdetails one at a time:
// sparkles appear and stay rather than being redrawn. Each draw (cell, bin)
// must enter once: the same draw read twice would count its microdetails
// twice, correlated.

// The count over the footprint's microdetails, and what turns it into a
// slope density: count / (total binArea).
struct GlintCount {
  real count;    // microdetails that reflect at h, each weighted by its lobe
  real total;    // N, the microdetails of the footprint
  real binArea;  // w^2, the slope area one microdetail's count spreads over
};

// N: the footprint's area on the surface in level-0 cells (one microdetail
// each in expectation), at least one: a pixel smaller than a microdetail
// sees at most that one.
real glintFootprintMicrodetails(vec2 dx, vec2 dy, real areaScale) {
  return areaScale * max(abs(cross2(dx, dy)), real(1));
}

// One cell's share n of the footprint at hpp: sum_j t_j B(n, p_j) over the 4
// bins around hpp, t_j their bilinear weights. The weights are not a filter
// to undo: they are each microdetail's lobe, the tent that realises D_l
// (docs/glints.md, "Why the expectation is D_g"), and the reference's point
// evaluation (glintCellDensity) applies the same. A microdetail whose slope
// lies near a bin's edge lights the pixel partly, as it lights the
// reference's. Distributing n over the bins instead (B(n t_j, p_j)) kept the
// mean but made each microdetail's lobe a random top-hat: its light went to
// fewer, brighter pixels, and the models showed 0.4-0.8 of the reference's
// sparkles (glint-plane under dolly, contrast 3).
real glintCellCount(GlintMaterial g, uint ch, vec2 hpp, real n, real w) {
  if (!(n > real(0))) return real(0);
  vec2 a = clampAlpha(g.alpha);
  vec2 offset = vec2(glintUniform(ch), glintUniform(glintHash(ch)));
  vec2 t = hpp / w - offset - vec2(real(0.5), real(0.5));  // bin b's centre at t = b
  vec2 b0 = floor(t);
  vec2 f = t - b0;
  vec2 e0 = (b0 + offset) * w;
  real px0 = glintInterval(e0.x, e0.x + w, a.x);
  real px1 = glintInterval(e0.x + w, e0.x + real(2) * w, a.x);
  real py0 = glintInterval(e0.y, e0.y + w, a.y);
  real py1 = glintInterval(e0.y + w, e0.y + real(2) * w, a.y);
  ivec2 i0 = ivec2(b0);
  real k = (real(1) - f.x) * (real(1) - f.y) * glintDraw(n, px0 * py0, glintBinHash(ch, i0));
  k += f.x * (real(1) - f.y) * glintDraw(n, px1 * py0, glintBinHash(ch, i0 + ivec2(1, 0)));
  k += (real(1) - f.x) * f.y * glintDraw(n, px0 * py1, glintBinHash(ch, i0 + ivec2(0, 1)));
  k += f.x * f.y * glintDraw(n, px1 * py1, glintBinHash(ch, i0 + ivec2(1, 1)));
  return k;
}

// glints-zk16's probe i along the footprint's long axis (level-0 cells).
vec2 glintProbe(vec2 p, GlintLod lod, int i) {
  return p + lod.step * (real(i) + real(0.5) - real(0.5) * real(lod.probes));
}

// The bilinear weight of cell c at q (cell units, centres at integers).
real glintTent(vec2 q, ivec2 c) {
  vec2 d = abs(q - vec2(c));
  return max(real(1) - d.x, real(0)) * max(real(1) - d.y, real(0));
}

// glints-zk16-counting at one level: the footprint's share n of microdetails
// distributed over the cells its probes read, with the weights of zk16's
// blend (1/probes times each probe's bilinear weights). Probes closer than
// two cells share cells; a cell's draw is made once, by the first probe that
// reads it, with the weights of all the probes that do (those form a run:
// the probes lie on a line).
real glintCountingLevel(GlintMaterial g, int level, vec2 p, GlintLod lod, vec2 hpp, real n, real w) {
  if (!(n > real(0))) return real(0);
  real size = exp2(real(level));
  vec2 centre = vec2(real(0.5), real(0.5));
  real share = n / real(lod.probes);
  real count = real(0);
  SHIMMER_DONT_UNROLL
  for (int i = 0; i < lod.probes; i++) {
    vec2 q = glintProbe(p, lod, i) / size - centre;
    vec2 before = glintProbe(p, lod, i - 1) / size - centre;
    ivec2 c0 = ivec2(floor(q));
    for (int c = 0; c < 4; c++) {
      ivec2 cell = c0 + ivec2(c & 1, c >> 1);
      real weight = glintTent(q, cell);
      if (!(weight > real(0)) || (i > 0 && glintTent(before, cell) > real(0))) continue;
      SHIMMER_DONT_UNROLL
      for (int j = i + 1; j < lod.probes; j++) {
        real wj = glintTent(glintProbe(p, lod, j) / size - centre, cell);
        if (!(wj > real(0))) break;
        weight += wj;
      }
      count += glintCellCount(g, glintCellHash(level, cell), hpp, share * weight, w);
    }
  }
  return count;
}

// ---- glints-db23: anisotropic grids ------------------------------------------
// Deliot and Belcour (HPG 2023), the grids of their title: instead of
// probing an isotropic level along the footprint, read grids whose cells have
// the footprint's shape: side 2^L across its short axis, 2^L rho along the
// long one, turned to its direction. L (levels), rho (powers of 2 up to
// GLINT_DB23_MAX_RATIO) and the direction (pi / (2 rho) apart: a longer cell
// needs finer turns) are discrete; the footprint reads the grids around its
// own L, rho and direction, linearly interpolated, and in each grid the 3
// cells of a triangular lattice around its centre (barycentric). Each grid
// and cell is a draw of its own, so the interpolation weights distribute the
// count without drawing any (cell, bin) twice.
const int GLINT_DB23_MAX_RATIO_LOG2 = 6;  // cells up to 64 times longer than wide

// The footprint's axes (level-0 cells), as glintLod: the eigenvectors of
// dx dx^T + dy dy^T, the major length and the minor = area / major.
struct GlintEllipse {
  real major;
  real minor;
  real angle;  // of the long axis, in [0, pi)
};

GlintEllipse glintEllipse(vec2 dx, vec2 dy) {
  real xx = dx.x * dx.x + dy.x * dy.x;
  real yy = dx.y * dx.y + dy.y * dy.y;
  real xy = dx.x * dx.y + dy.x * dy.y;
  real half_trace = real(0.5) * (xx + yy);
  real root = sqrt(sqr(real(0.5) * (xx - yy)) + xy * xy);
  GlintEllipse e;
  e.major = sqrt(half_trace + root);
  e.minor = e.major > real(0) ? abs(cross2(dx, dy)) / e.major : real(0);
  e.angle = real(0);
  if (root > real(0)) {
    vec2 v = xx >= yy ? vec2(half_trace + root - yy, xy) : vec2(xy, half_trace + root - xx);
    if (length(v) > real(0)) e.angle = atan(v.y, v.x);
  }
  if (e.angle < real(0)) e.angle += PI;
  if (!(e.angle < PI)) e.angle = real(0);
  return e;
}

// One grid's share n: the footprint centre p (level-0 cells) in the grid of
// level L, ratio 2^e and direction index k, and the 3 lattice cells around
// it. The lattice's rows are one cell apart across the long axis, its cells
// rho 2^L long along it, the rows shifted by half a cell (a triangular
// lattice: 3 cells, not 4, carry a point's barycentric weights).
real glintDb23Grid(GlintMaterial g, int level, int e, int k, vec2 p, vec2 hpp, real n, real w) {
  if (!(n > real(0))) return real(0);
  real rho = exp2(real(e));
  real angle = real(k) * PI / (real(2) * rho);
  vec2 along = vec2(cos(angle), sin(angle));
  vec2 across = vec2(-along.y, along.x);
  real size = exp2(real(level));
  // (a, b): the lattice's skewed coordinates, rows b across the long axis.
  real y = dot(p, across) / (size * real(0.86602540378443865));
  real x = dot(p, along) / (size * rho) - real(0.5) * y;
  vec2 lim = vec2(real(1e9), real(1e9));
  vec2 s = clamp(vec2(x, y), -lim, lim);
  vec2 s0 = floor(s);
  vec2 f = s - s0;
  ivec2 c = ivec2(s0);
  uint grid = glintHash(uint(k) ^ glintHash(uint(e) ^ glintHash(uint(level) + 0x632be5abu)));
  bool lower = f.x + f.y < real(1);  // the triangle (c, c + x, c + y), else (c + x + y, c + x, c + y)
  real count = real(0);
  // One loop over the 3 cells, not 3 calls: each inlined copy of the
  // cell's 4 binomial draws multiplies the kernel, and 30 copies (2 levels,
  // up to 5 grids, 3 cells) stalled lavapipe's compiler for minutes.
  SHIMMER_DONT_UNROLL
  for (int i = 0; i < 3; i++) {
    ivec2 cell = i == 0 ? (lower ? c : c + ivec2(1, 1)) : (i == 1 ? c + ivec2(1, 0) : c + ivec2(0, 1));
    real weight = i == 0 ? (lower ? real(1) - f.x - f.y : f.x + f.y - real(1))
                         : (i == 1 ? (lower ? f.x : real(1) - f.y) : (lower ? f.y : real(1) - f.x));
    count += glintCellCount(g, glintGridCellHash(grid, cell), hpp, n * weight, w);
  }
  return count;
}

// The 3 grids of one level around the footprint's ratio and direction, and
// their weights. Ratio 2^e0 has directions pi / (2 rho0) apart, 2^(e0+1)
// twice as many: in (f, s), f the position between directions k and k + 1
// of ratio e0 and s between the two ratios, the cell is a trapezoid with
// corners B0, B1 (ratio e0) and T0, Th, T1 (ratio e0 + 1 at 2k, 2k + 1,
// 2k + 2), cut into the triangles (B0 T0 Th), (B0 Th B1), (B1 Th T1).
// Linear in each, continuous across them, across directions and across
// ratios (s = 1 there is s = 0 of the next ratio, on the same directions).
// Ratio 1 is isotropic: one grid, direction 0.
real glintDb23Level(GlintMaterial g, int level, GlintEllipse el, real cellMinor, vec2 p, vec2 hpp, real n, real w) {
  if (!(n > real(0))) return real(0);
  real r = clamp(max(el.major, cellMinor) / cellMinor, real(1), exp2(real(GLINT_DB23_MAX_RATIO_LOG2)));
  int e0 = min(int(floor(log2(r))), GLINT_DB23_MAX_RATIO_LOG2 - 1);
  real rho0 = exp2(real(e0));
  real s = clamp((r - rho0) / rho0, real(0), real(1));
  int turns0 = 2 * int(rho0);  // directions of ratio e0 in [0, pi)
  real u = el.angle / (PI / real(turns0));
  int k = min(int(floor(u)), turns0 - 1);
  real f = clamp(u - real(k), real(0), real(1));
  real wB0, wB1, wT0, wTh, wT1;
  if (f < real(0.5) * s) {
    wTh = real(2) * f;
    wT0 = s - wTh;
    wB0 = real(1) - s;
    wB1 = real(0);
    wT1 = real(0);
  } else if (f > real(1) - real(0.5) * s) {
    wTh = real(2) * (real(1) - f);
    wT1 = s - wTh;
    wB1 = real(1) - s;
    wB0 = real(0);
    wT0 = real(0);
  } else {
    wTh = s;
    wB1 = f - real(0.5) * s;
    wB0 = real(1) - f - real(0.5) * s;
    wT0 = real(0);
    wT1 = real(0);
  }
  int kB0 = k;
  int kB1 = k + 1 == turns0 ? 0 : k + 1;
  if (e0 == 0) {  // ratio 1: B0 and B1 are the one isotropic grid
    wB0 += wB1;
    wB1 = real(0);
    kB0 = 0;
  }
  int turns1 = 2 * turns0;
  int kT1 = 2 * k + 2 == turns1 ? 0 : 2 * k + 2;
  real count = real(0);
  SHIMMER_DONT_UNROLL
  for (int i = 0; i < 5; i++) {  // B0, B1, T0, Th, T1: one copy of the grid's code
    real weight = i == 0 ? wB0 : (i == 1 ? wB1 : (i == 2 ? wT0 : (i == 3 ? wTh : wT1)));
    int ratio = i < 2 ? e0 : e0 + 1;
    int turn = i == 0 ? kB0 : (i == 1 ? kB1 : (i == 2 ? 2 * k : (i == 3 ? 2 * k + 1 : kT1)));
    if (weight > real(0)) count += glintDb23Grid(g, level, ratio, turn, p, hpp, n * weight, w);
  }
  return count;
}

// ---- glints-points: point microdetails at their own half vectors ------------
// shimmer's own model (docs/glints.md, "glints-points"). The counting models
// above shade every microdetail of the footprint at the pixel centre's half
// vector, and give every pixel that reads a cell a share of that cell's
// microdetails drawn with the cell's one uniform. On a curved surface the
// half vector changes by about a slope bin across a pixel, so a microdetail
// lights or goes dark whenever the pixel centre it is read with changes:
// under dolly their sparkles lived 0.56-0.88 of the reference's. Here the
// microdetails are points, as in the reference: a cell draws its count per
// slope bin once (B(n, p_bin), n the cell's own expected microdetails), places
// each at a uniform point of the cell, and a pixel counts those inside its
// footprint (the parallelogram the pixel's box maps to), each weighted by its
// lobe at the half vector of the point where it lies, hpp + a dhpp/dx +
// b dhpp/dy at footprint coordinates (a, b). A point lies in one pixel and
// keeps its half vector as it crosses into the next: it is lit until its
// half vector leaves its bin's lobe, as the reference's are.
//
// Counting: each of the cell's k points lies in the footprint with the
// probability of the overlap's share of the cell, independently, so the
// pixel's count is the cell counts thinned by area, which keeps the
// binomial law over the footprint's N = area x density microdetails (for a
// constant half vector, the same lobe-weighted law as the other counting
// models). Levels: a cell about the footprint's short axis wide (at least
// 1/16 of the long axis, as glintLod), trilinear between two levels by
// which points exist: a point at level l0 exists when its own uniform is
// below 1 - t, at l0 + 1 below t, so the expected count is N m1 at any t
// and a point born or dying as t moves is the only change.
const int GLINT_POINTS_MAX_CELLS = 96;  // cells one level of a footprint reads (a 16:1 footprint reads ~40)
const int GLINT_POINTS_MAX_BINS = 8;    // slope bins per axis: the footprint's spread of half vectors (+- 3 bins)
const int GLINT_POINTS_MAX_PLACED = 32; // points placed per (cell, bin); beyond, the covered share draws them

// A footprint as glints-points reads it, in level-0 cells: centre p, axes
// dx, dy (per pixel) and the rows of their inverse (a point q lies at
// footprint coordinates (dot(toA, q - p), dot(toB, q - p))), and the half
// vector at the centre with its change per pixel.
struct GlintPointsFootprint {
  vec2 p;
  // The centre in world-scaled uv and the level-0 cell's side: a point's
  // offset from the centre is formed in uv, where float holds the position
  // about 6 times finer than in cell units (~2000 cells on glint-sphere),
  // since the half vector at the point multiplies that offset's error.
  vec2 uv;
  real cellSize;
  vec2 dx;
  vec2 dy;
  vec2 toA;
  vec2 toB;
  vec2 hpp;
  vec2 dhppdx;
  vec2 dhppdy;
};

// The x-range of the parallelogram v0 v1 v2 v3 (in order) within the band
// y0 <= y <= y1: its corners in the band and its edges' crossings of y0, y1.
vec2 glintBandRange(vec2 v0, vec2 v1, vec2 v2, vec2 v3, real y0, real y1) {
  real lo = real(1e30);
  real hi = real(-1e30);
  for (int i = 0; i < 4; i++) {
    vec2 a = i == 0 ? v0 : (i == 1 ? v1 : (i == 2 ? v2 : v3));
    vec2 b = i == 0 ? v1 : (i == 1 ? v2 : (i == 2 ? v3 : v0));
    if (a.y >= y0 && a.y <= y1) {
      lo = min(lo, a.x);
      hi = max(hi, a.x);
    }
    for (int k = 0; k < 2; k++) {
      real y = k == 0 ? y0 : y1;
      if ((a.y - y) * (b.y - y) <= real(0) && a.y != b.y) {
        real x = a.x + (b.x - a.x) * (y - a.y) / (b.y - a.y);
        lo = min(lo, x);
        hi = max(hi, x);
      }
    }
  }
  return vec2(lo, hi);
}

// The share of the unit cell `cell` (in the units of the corners) that the
// parallelogram v0 v1 v2 v3 covers (.x), and the covered part's centroid
// (.yz): its height over 16 columns of the cell (midpoint rule; continuous
// as the parallelogram moves, within about 1 % of the exact share).
vec3 glintCellCover(vec2 v0, vec2 v1, vec2 v2, vec2 v3, ivec2 cell) {
  const int columns = 16;
  real area = real(0);
  vec2 moment = vec2(real(0), real(0));
  for (int i = 0; i < columns; i++) {
    real x = real(cell.x) + (real(i) + real(0.5)) / real(columns);
    // The parallelogram's extent along y at x: the band routine with the axes swapped.
    vec2 r = glintBandRange(vec2(v0.y, v0.x), vec2(v1.y, v1.x), vec2(v2.y, v2.x), vec2(v3.y, v3.x), x, x);
    real lo = max(r.x, real(cell.y));
    real hi = min(r.y, real(cell.y + 1));
    if (!(hi > lo)) continue;
    area += hi - lo;
    moment += vec2(x * (hi - lo), real(0.5) * (hi * hi - lo * lo));
  }
  if (!(area > real(0))) return vec3(real(0), real(cell.x) + real(0.5), real(cell.y) + real(0.5));
  return vec3(area / real(columns), moment.x / area, moment.y / area);
}

// The lobe-weighted count of one cell's points inside the footprint: n the
// cell's expected microdetails, `exist` the share of this level.
real glintPointsCell(GlintMaterial g, int level, ivec2 cell, GlintPointsFootprint f, vec3 cover, real n, real w,
                     real exist) {
  vec2 a = clampAlpha(g.alpha);
  uint ch = glintCellHash(level, cell);
  vec2 offset = vec2(glintUniform(ch), glintUniform(glintHash(ch)));
  vec2 t = f.hpp / w - offset - vec2(real(0.5), real(0.5));  // bin b's centre at t = b, as glintCellCount
  vec2 tx = f.dhppdx / w;
  vec2 ty = f.dhppdy / w;
  vec2 reach = real(0.5) * (abs(tx) + abs(ty));  // the footprint's half spread of t
  ivec2 lo = ivec2(floor(t - reach));
  ivec2 hi = min(ivec2(floor(t + reach)) + ivec2(1, 1), lo + ivec2(GLINT_POINTS_MAX_BINS - 1));
  real size = exp2(real(level));
  real count = real(0);
  SHIMMER_DONT_UNROLL
  for (int by = lo.y; by <= hi.y; by++) {
    real py = glintInterval((real(by) + offset.y) * w, (real(by) + offset.y + real(1)) * w, a.y);
    SHIMMER_DONT_UNROLL
    for (int bx = lo.x; bx <= hi.x; bx++) {
      real px = glintInterval((real(bx) + offset.x) * w, (real(bx) + offset.x + real(1)) * w, a.x);
      uint bh = glintBinHash(ch, ivec2(bx, by));
      real k = glintDraw(n, px * py, bh);
      if (k > real(GLINT_POINTS_MAX_PLACED)) {
        // Many points: how many lie inside is B(k, the covered share),
        // drawn once per (cell, bin), lit at the covered part's centroid.
        real inside = glintBinomial(k, cover.x * exist, glintUniform(glintHash(bh ^ 0x5bd1e995u)), real(0.5));
        vec2 centre = (vec2(cover.y, cover.z) * (size * f.cellSize) - f.uv) / f.cellSize;
        vec2 at = t + dot(f.toA, centre) * tx + dot(f.toB, centre) * ty;
        count += inside * max(real(1) - abs(at.x - real(bx)), real(0)) * max(real(1) - abs(at.y - real(by)), real(0));
        continue;
      }
      int placed = int(k);
      real lit = real(0);
      SHIMMER_DONT_UNROLL
      for (int j = 0; j < placed; j++) {
        uint hx = glintHash(bh ^ (uint(j) * 0x9e3779b9u + 0x85ebca6bu));
        uint hy = glintHash(hx);
        if (!(glintUniform(glintHash(hy)) < exist)) continue;
        vec2 q = ((vec2(cell) + vec2(glintUniform(hx), glintUniform(hy))) * (size * f.cellSize) - f.uv) / f.cellSize;
        real fa = dot(f.toA, q);
        real fb = dot(f.toB, q);
        if (!(abs(fa) <= real(0.5) && abs(fb) <= real(0.5))) continue;
        vec2 at = t + fa * tx + fb * ty;  // the point's own half vector, in bins
        lit += max(real(1) - abs(at.x - real(bx)), real(0)) * max(real(1) - abs(at.y - real(by)), real(0));
      }
      count += lit;
    }
  }
  return count;
}

// One level's points in the footprint: the cells it overlaps, row by row
// (each cell once), `exist` the level's share.
real glintPointsLevel(GlintMaterial g, int level, GlintPointsFootprint f, real areaScale, real w, real exist) {
  if (!(exist > real(0))) return real(0);
  real size = exp2(real(level));
  real n = areaScale * size * size;
  vec2 v0 = (f.p - real(0.5) * f.dx - real(0.5) * f.dy) / size;
  vec2 v1 = (f.p + real(0.5) * f.dx - real(0.5) * f.dy) / size;
  vec2 v2 = (f.p + real(0.5) * f.dx + real(0.5) * f.dy) / size;
  vec2 v3 = (f.p - real(0.5) * f.dx + real(0.5) * f.dy) / size;
  int y0 = int(floor(min(min(v0.y, v1.y), min(v2.y, v3.y))));
  int y1 = int(floor(max(max(v0.y, v1.y), max(v2.y, v3.y))));
  real count = real(0);
  int cells = 0;
  SHIMMER_DONT_UNROLL
  for (int cy = y0; cy <= y1 && cells < GLINT_POINTS_MAX_CELLS; cy++) {
    vec2 r = glintBandRange(v0, v1, v2, v3, real(cy), real(cy + 1));
    if (!(r.x <= r.y)) continue;
    SHIMMER_DONT_UNROLL
    for (int cx = int(floor(r.x)); cx <= int(floor(r.y)) && cells < GLINT_POINTS_MAX_CELLS; cx++) {
      cells++;
      count += glintPointsCell(g, level, ivec2(cx, cy), f, glintCellCover(v0, v1, v2, v3, ivec2(cx, cy)), n, w, exist);
    }
  }
  return count;
}

// glints-points' count for the footprint (dx, dy in level-0 cells, p its
// centre). A footprint under one cell is read as a cell-sized square of its
// orientation: N counts it as one microdetail's area (glintFootprintMicrodetails).
real glintPointsCount(GlintMaterial g, vec2 uv, real cellSize, vec2 p, vec2 dx, vec2 dy, vec2 hpp, vec2 dhppdx,
                      vec2 dhppdy, real areaScale, real w) {
  real area = abs(cross2(dx, dy));
  if (!(area >= real(1))) {
    if (area > real(1e-12)) {
      dx /= sqrt(area);
      dy /= sqrt(area);
    } else {
      dx = vec2(real(1), real(0));
      dy = vec2(real(0), real(1));
    }
  }
  real det = dx.x * dy.y - dx.y * dy.x;
  GlintPointsFootprint f;
  f.p = p;
  f.uv = uv;
  f.cellSize = cellSize;
  f.dx = dx;
  f.dy = dy;
  f.toA = vec2(dy.y, -dy.x) / det;
  f.toB = vec2(-dx.y, dx.x) / det;
  f.hpp = hpp;
  f.dhppdx = glintFinite(dhppdx);
  f.dhppdy = glintFinite(dhppdy);
  GlintEllipse el = glintEllipse(dx, dy);
  real cellMinor = max(max(el.minor, el.major / real(GLINT_MAX_ANISOTROPY)), real(1));
  real level = clamp(log2(cellMinor), real(0), real(GLINT_MAX_LEVEL));
  int l0 = min(int(floor(level)), GLINT_MAX_LEVEL - 1);
  real t = level - real(l0);
  return glintPointsLevel(g, l0, f, areaScale, w, real(1) - t) + glintPointsLevel(g, l0 + 1, f, areaScale, w, t);
}

// The count of the three models that keep the binomial law (GLINT_COUNTING,
// GLINT_DB23, GLINT_POINTS) for the footprint fp at hpp.
GlintCount glintCountedDraws(int mode, GlintMaterial g, vec2 hpp, GlintFootprint fp) {
  GlintCount o;
  real w = real(1.41421356237309505) * clamp(g.alphaL, ALPHA_MIN, ALPHA_MAX);
  o.binArea = w * w;
  o.count = real(0);
  o.total = real(1);
  if (!(g.density > real(0))) return o;
  real cell = inversesqrt(g.density);
  vec2 lim = vec2(real(1e9), real(1e9));
  vec2 p = clamp(fp.uv / cell, -lim, lim);
  if (!(p.x == p.x) || !(p.y == p.y)) p = vec2(real(0), real(0));
  real areaScale = max(fp.areaScale, real(1e-6));
  if (!(areaScale < real(1e15))) areaScale = real(1e15);
  vec2 dx = glintFinite(fp.duvdx / cell);
  vec2 dy = glintFinite(fp.duvdy / cell);
  o.total = glintFootprintMicrodetails(dx, dy, areaScale);
  if (mode == GLINT_POINTS) {
    // The uv itself where p is its unclamped quotient (finer in float than p * cell).
    vec2 uv = p == fp.uv / cell ? fp.uv : p * cell;
    o.count = glintPointsCount(g, uv, cell, p, dx, dy, hpp, fp.dhppdx, fp.dhppdy, areaScale, w);
    return o;
  }
  if (mode == GLINT_COUNTING) {
    GlintLod lod = glintLod(dx, dy);
    real level = clamp(lod.level, real(0), real(GLINT_MAX_LEVEL));
    int l0 = min(int(floor(level)), GLINT_MAX_LEVEL - 1);
    real t = level - real(l0);
    o.count = glintCountingLevel(g, l0, p, lod, hpp, o.total * (real(1) - t), w) +
              glintCountingLevel(g, l0 + 1, p, lod, hpp, o.total * t, w);
    return o;
  }
  GlintEllipse el = glintEllipse(dx, dy);
  real cellMinor = max(max(el.minor, el.major / exp2(real(GLINT_DB23_MAX_RATIO_LOG2))), real(1));
  real level = clamp(log2(cellMinor), real(0), real(GLINT_MAX_LEVEL));
  int l0 = min(int(floor(level)), GLINT_MAX_LEVEL - 1);
  real t = level - real(l0);
  // The two levels' counts, summed as the C++ model sums them (0 + L0 is L0).
  o.count = real(0);
  SHIMMER_DONT_UNROLL
  for (int i = 0; i < 2; i++)
    o.count += glintDb23Level(g, l0 + i, el, cellMinor, p, hpp, o.total * (i == 0 ? real(1) - t : t), w);
  return o;
}

FilteredNdf glintCountedNdf(int mode, GlintMaterial g, vec2 hpp, GlintFootprint fp) {
  FilteredNdf o;
  o.alpha_eff = glintGlobalAlpha(g);
  hpp = clampSlope(hpp);
  if (!(g.density > real(0))) {
    o.slope_density = slopeDensity(NDF_BECKMANN, hpp, o.alpha_eff);
    o.density = o.slope_density * slopeToSolidAngle(hpp);
    return o;
  }
  GlintCount c = glintCountedDraws(mode, g, hpp, fp);
  o.slope_density = c.count / (c.total * c.binArea);
  o.density = o.slope_density * slopeToSolidAngle(hpp);
  return o;
}

FilteredNdf glintNdf(int mode, GlintMaterial g, vec2 hpp, GlintFootprint fp) {
#ifdef SHIMMER_COUNTED_GLINTS
  if (mode == GLINT_COUNTING || mode == GLINT_DB23 || mode == GLINT_POINTS) return glintCountedNdf(mode, g, hpp, fp);
#endif
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

// The count a mode gives over the footprint's N microdetails at hpp. For the
// blending modes (glints-zk16, none, glints-naive) and D_g, the count that
// their slope density stands for: slope_density N w^2, so that every mode's
// count is compared with the same binomial law (glints_test.cpp).
GlintCount glintCount(int mode, GlintMaterial g, vec2 hpp, GlintFootprint fp) {
  if (mode == GLINT_COUNTING || mode == GLINT_DB23 || mode == GLINT_POINTS)
    return glintCountedDraws(mode, g, clampSlope(hpp), fp);
  GlintCount o;
  real w = real(1.41421356237309505) * clamp(g.alphaL, ALPHA_MIN, ALPHA_MAX);
  o.binArea = w * w;
  real cell = g.density > real(0) ? inversesqrt(g.density) : real(1);
  real areaScale = clamp(fp.areaScale, real(1e-6), real(1e15));
  o.total = glintFootprintMicrodetails(glintFinite(fp.duvdx / cell), glintFinite(fp.duvdy / cell), areaScale);
  o.count = glintNdf(mode, g, hpp, fp).slope_density * o.total * o.binArea;
  return o;
}

// The glint mode a variant shades a glint material with (variants.glsl).
int glintModeOf(int variant) {
  int v = geometricVariant(variant);
  if (v == VARIANT_GLINTS_ZK16) return GLINT_FILTERED;
  if (v == VARIANT_GLINTS_NAIVE) return GLINT_NAIVE;
  if (v == VARIANT_GLINTS_SMOOTH) return GLINT_SMOOTH;
  // Selects, not branches: the kernels of the variants above fold them away
  // without a trace, so their SPIR-V (and job ids) stay as they were.
  return v == VARIANT_GLINTS_ZK16_COUNTING
             ? GLINT_COUNTING
             : (v == VARIANT_GLINTS_DB23 ? GLINT_DB23 : (v == VARIANT_GLINTS_POINTS ? GLINT_POINTS : GLINT_POINT));
}
