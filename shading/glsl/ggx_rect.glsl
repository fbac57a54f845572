// Mean of the anisotropic GGX slope density over an axis-aligned rectangle
// [c.x - f.x, c.x + f.x] x [c.y - f.y, c.y + f.y] in slope space (seed 000,
// "Filtering GGX NDF" / "Convolving with GGX").
//
// In normalised slopes u = x / ax, w = y / ay the density is
// (1 + u^2 + w^2)^-2 / (pi ax ay), so every function below works on
// M(uc, wc, fu, fw) = mean of (1 + u^2 + w^2)^-2 over the normalised rectangle.

// The closed form of seed 000 (GGXRectIntegral, without its Jacobian). The
// slide's normalisation "2*M_Pi*f" has f = 1: the bracket is dimensionless and
// the result must have the dimension of 1 / (x2 - x1)(y2 - y1); quadrature
// agrees (tests/shading/ggx_rect_test.cpp). It is a double difference of O(1)
// corner terms, so it cancels catastrophically for small or distant
// rectangles; seed 000 clamps the footprint from below for that reason.
real ggxRectMeanSeed(vec2 hpp, vec2 roughness, vec2 footprint) {
  real a = roughness.x;
  real b = roughness.y;
  real a_2 = a * a;
  real b_2 = b * b;
  real x1 = hpp.x - footprint.x;
  real x2 = hpp.x + footprint.x;
  real y1 = hpp.y - footprint.y;
  real y2 = hpp.y + footprint.y;
  real x1_2 = x1 * x1;
  real x2_2 = x2 * x2;
  real y1_2 = y1 * y1;
  real y2_2 = y2 * y2;
  // Same operations as the slide, regrouped only where its parentheses do not
  // balance: (A + B + C) / (2 pi (x1 - x2)(y1 - y2)).
  real A = (x1 * (atan((y1 * a) / (sqrt(x1_2 + a_2) * b)) - atan((y2 * a) / (sqrt(x1_2 + a_2) * b)))) /
           sqrt(x1_2 + a_2);
  real B = (x2 * (-atan((y1 * a) / (sqrt(x2_2 + a_2) * b)) + atan((y2 * a) / (sqrt(x2_2 + a_2) * b)))) /
           sqrt(x2_2 + a_2);
  real C = (y1 * sqrt(y2_2 + b_2) *
                (atan((x1 * b) / (a * sqrt(y1_2 + b_2))) - atan((x2 * b) / (a * sqrt(y1_2 + b_2)))) +
            y2 * sqrt(y1_2 + b_2) *
                (-atan((x1 * b) / (a * sqrt(y2_2 + b_2))) + atan((x2 * b) / (a * sqrt(y2_2 + b_2))))) /
           (sqrt((y1_2 + b_2) * (y2_2 + b_2)));
  real val = (A + B + C) / ((real(2) * PI) * (x1 - x2) * (y1 - y2));
  return val;
}

// ---------------------------------------------------------------------------
// Numerically stable rectangle mean (ours; "k16-ggx-rect-stable").
//
// The integral over w is done in closed form with w = c tan(psi):
//   int_{w1}^{w2} dw / (c^2 + w^2)^2
//     = (1 / 2c^3) [ (dpsi - sin dpsi) + 2 cos^2((psi1 + psi2) / 2) sin dpsi ]
// where dpsi = psi2 - psi1 = atan2((w2 - w1) c, c^2 + w1 w2) (arctangent
// difference identity: no subtraction of nearly equal angles) and
// cos((psi1 + psi2) / 2) = sin((atan2(c, w1) + atan2(c, w2)) / 2) for the
// half with w1 + w2 >= 0. Both bracket terms are non-negative, so nothing
// cancels. The outer integral over u uses u = C tan(phi) with
// C = sqrt(1 + w_near^2), which turns the algebraic tails into smooth
// functions of phi, and a Gauss-Legendre rule on phi (4 points when the
// angular width is below 0.3, else 8). The outer
// direction is the one with the smaller angular width. Every width is
// carried as a half-side, never as the difference of two corners, and ratios
// like dpsi / dw are formed without dividing two vanishing numbers, so
// footprints down to zero work. Footprints small against their distance from
// the lobe's poles (most of a frame's) take the tensor rule below instead.
//
// Bound: relative error <= 1e-4 in float32 against a 30-digit oracle over
// alpha 1e-3..1, half-sides 1e-6..10 (unequal too), centres up to 100 alpha
// and slopes up to 6 (tests assert 1e-3). Cost: the tensor rule's 16 to 64
// divisions, and where it does not hold 4 or 8 inner evaluations, each one
// atan and three sqrt (see ggxRectInnerTerms), and a tan per node.

// Distance from 0 to the interval [xc - f, xc + f] (0 when it contains 0).
real intervalNear(real xc, real f) { return max(abs(xc) - f, real(0)); }

// Gauss-Legendre nodes (Y) and weights (W) on [-1, 1]: 4 points at +-Y0,
// +-Y1 and 8 points at +-Y0..+-Y3.
const real GL4_Y0 = real(0.3399810435848563), GL4_W0 = real(0.6521451548625461);
const real GL4_Y1 = real(0.8611363115940526), GL4_W1 = real(0.3478548451374538);
const real GL8_Y0 = real(0.1834346424956498), GL8_W0 = real(0.3626837833783620);
const real GL8_Y1 = real(0.5255324099163290), GL8_W1 = real(0.3137066458778873);
const real GL8_Y2 = real(0.7966664774136267), GL8_W2 = real(0.2223810344533745);
const real GL8_Y3 = real(0.9602898564975363), GL8_W3 = real(0.1012285362903763);

// vec2(node, weight) of the k-th positive node of the n-point
// Gauss-Legendre rule (n = 4 or 8; the nodes come in pairs +-node).
vec2 gaussLegendrePair(int n, int k) {
  if (n == 4) return k == 0 ? vec2(GL4_Y0, GL4_W0) : vec2(GL4_Y1, GL4_W1);
  return k == 0 ? vec2(GL8_Y0, GL8_W0) : k == 1 ? vec2(GL8_Y1, GL8_W1) : k == 2 ? vec2(GL8_Y2, GL8_W2) : vec2(GL8_Y3, GL8_W3);
}

// ---------------------------------------------------------------------------
// Footprints small against their distance from the lobe's poles: a
// Gauss-Legendre tensor rule on the rectangle itself (ours; shared by both
// rects).
//
// In normalised slopes both rects average g = (J / q)^2 with q = 1 + u^2 + w^2
// and J = 1 + ax2 u^2 + ay2 w^2 (ax2 = ay2 = 0: the stable rect's 1 / q^2).
// g is rational and positive, and its only singularities are q's zeros: for
// real w, u = +-i sqrt(1 + w^2), at least R = sqrt(1 + un^2 + wn^2) from every
// point of the rectangle (un, wn: the rectangle's distances from the axes),
// and likewise in w. So an n-point Gauss-Legendre rule over a half-side f
// converges like (2 R / f)^-2n, with no arctangent and no change of
// variables: a term costs one division, where the rules further down take an
// arctangent, a square root and several divisions per row. Each direction
// takes 4 points where its half-side is below TENSOR_KAPPA4 R and 8 where it
// is below TENSOR_KAPPA8 R; larger footprints take the rules below. Most
// pixels of a frame qualify: away from the highlight R is large.
//
// The Jacobian's numerator adds one condition for the 4-point rule. Where its
// anisotropic part (ax2 - m) u^2 + (ay2 - m) w^2 outgrows the isotropic 1 - m
// (m the smaller squared roughness), g grows like u^4 towards the
// rectangle's edges, the mean sits in the rule's weakest terms, and the
// error grows several-fold (to 2.6e-5 at equality); TENSOR_LAMBDA bounds that
// part, and the 8-point rule takes the rest. The constants were tuned on
// 200000 random qualifying rectangles per setting (alpha 1e-3..1, anisotropy
// to 1000:1, centres to slope 8) against the rules below in double: 4 points
// at kappa 0.25: worst 2.5e-6 for either rect (7.7e-6 at 0.3, 2e-5 at 0.35);
// 8 points at kappa 0.75: below 2.5e-6 (1e-5 at kappa 1).
const real TENSOR_KAPPA4 = real(0.25);
const real TENSOR_KAPPA8 = real(0.75);
const real TENSOR_LAMBDA = real(0.25);

// The tensor rule's points along u and w for the normalised rectangle
// [uc +- fu] x [wc +- fw] (4 or 8 each), or ivec2(0) where it does not hold;
// eu = ax2 - m, ew = ay2 - m and m = min(ax2, ay2) (all 0 for the stable rect).
ivec2 tensorRulePoints(real uc, real wc, real fu, real fw, real eu, real ew, real m) {
  real un = intervalNear(uc, fu);
  real wn = intervalNear(wc, fw);
  real R2 = real(1) + un * un + wn * wn;
  real uf = abs(uc) + fu;
  real wf = abs(wc) + fw;
  if (max(fu, fw) > TENSOR_KAPPA8 * sqrt(R2)) return ivec2(0);
  bool mild = eu * uf * uf + ew * wf * wf <= TENSOR_LAMBDA * (real(1) - m);
  real k4 = TENSOR_KAPPA4 * TENSOR_KAPPA4 * R2;
  return ivec2(mild && fu * fu <= k4 ? 4 : 8, mild && fw * fw <= k4 ? 4 : 8);
}

// g at (u, w) from pu = 1 + u^2 and ju = 1 + ax2 u^2; the ratio is squared,
// not q, so nothing overflows for slopes up to SLOPE_MAX / ALPHA_MIN.
real tensorRuleTerm(real pu, real ju, real w, real ay2) {
  real w2 = w * w;
  real r = (ju + ay2 * w2) / (pu + w2);
  return r * r;
}

// The n-point rule over w in [wc +- fw] at u, as a weighted sum (the
// weights sum to 2).
real tensorRuleRow(real u, real wc, real fw, real ax2, real ay2, int n) {
  real pu = real(1) + u * u;
  real ju = real(1) + ax2 * u * u;
  real sum = real(0);
  for (int k = 0; k < n / 2; ++k) {
    vec2 node = gaussLegendrePair(n, k);
    sum += node.y * (tensorRuleTerm(pu, ju, wc - fw * node.x, ay2) + tensorRuleTerm(pu, ju, wc + fw * node.x, ay2));
  }
  return sum;
}

// Mean of g over the normalised rectangle by the tensor rule with
// points.x points along u and points.y along w. The loops' trip counts vary
// per pixel: a SIMD batch pays for its largest, not for the sum of both rules.
real tensorRuleMean(real uc, real wc, real fu, real fw, real ax2, real ay2, ivec2 points) {
  real sum = real(0);
  for (int k = 0; k < points.x / 2; ++k) {
    vec2 node = gaussLegendrePair(points.x, k);
    sum += node.y * (tensorRuleRow(uc - fu * node.x, wc, fw, ax2, ay2, points.y) +
                     tensorRuleRow(uc + fu * node.x, wc, fw, ax2, ay2, points.y));
  }
  return real(0.25) * sum;
}

// ---------------------------------------------------------------------------
// Larger footprints: a closed form along one axis, a quadrature along the other.

// atan2(d * c, den) / d for d >= 0, finite as d -> 0: where the angle is
// small (den > 0 and t = d c / den < 1e-3, which takes in every d that could
// underflow) its series, else the arctangent. One arctangent either way, as
// a select: lavapipe runs both sides of a branch between two forms.
real atanRatio(real d, real c, real den) {
  real t = d * c / den;
  return (den > real(0) && t < real(1e-3)) ? c / den * (real(1) - t * t / real(3)) : atan(d * c, den) / d;
}

// (x - sin x) / x for 0 <= x < 1 (Taylor series to x^10, truncation below
// 1e-10 relative).
real oneMinusSincTimesSmall(real x) {
  real x2 = x * x;
  return x2 * (real(1.0 / 6.0) -
               x2 * (real(1.0 / 120.0) -
                     x2 * (real(1.0 / 5040.0) - x2 * (real(1.0 / 362880.0) - x2 * real(1.0 / 39916800.0)))));
}

// The inner integrals over w in [wc - fw, wc + fw], with w = c tan(psi):
//   int dw / (c^2 + w^2)   = dpsi / c
//   int dw / (c^2 + w^2)^2 = (dpsi + sin(dpsi) cos(psi1 + psi2)) / (2 c^3).
// Returns vec2(r, B): r = dpsi / (w2 - w1) and
//   B = a + (1 + cos(psi1 + psi2)) b,  a = (dpsi - sin dpsi) / dpsi,  b = sin(dpsi) / dpsi,
// so that the means over the interval are r / c and B r / (2 c^3). Both terms
// of B are non-negative, so nothing cancels. Only dpsi takes an arctangent:
// sin(dpsi) = 2 fw c / (s1 s2) and cos(psi1 + psi2) = cos1 cos2 - sin1 sin2 are
// algebraic in the endpoints' cosines c / s_i and sines w_i / s_i
// (s_i = sqrt(c^2 + w_i^2)), and where sin1 sin2 > 0 the difference
// 1 - sin1 sin2 = (cos1^2 + cos2^2 sin1^2) / (1 + sin1 sin2) is a sum of
// squares. (Before, the sum angle took two more atan2 and a sin per call.)
vec2 ggxRectInnerTerms(real c, real wc, real fw) {
  wc = abs(wc);  // the integrand is even in w
  real w1 = wc - fw;
  real w2 = wc + fw;
  real r = atanRatio(real(2) * fw, c, c * c + w1 * w2);
  real dpsi = r * real(2) * fw;
  real is1 = inversesqrt(c * c + w1 * w1);
  real is2 = inversesqrt(c * c + w2 * w2);
  real cos1 = c * is1;
  real cos2 = c * is2;
  real sin1 = w1 * is1;
  real sin2 = w2 * is2;
  real b = cos1 * cos2 / (c * r);
  real a = dpsi < real(1) ? oneMinusSincTimesSmall(dpsi) : real(1) - b;
  real ss = sin1 * sin2;
  real oneMinusSs = ss > real(0) ? (cos1 * cos1 + cos2 * cos2 * sin1 * sin1) / (real(1) + ss) : real(1) - ss;
  return vec2(r, a + (cos1 * cos2 + oneMinusSs) * b);
}

// Mean over w in [wc - fw, wc + fw] of (c^2 + w^2)^-2.
real ggxRectInnerMean(real c, real wc, real fw) {
  vec2 t = ggxRectInnerTerms(c, wc, fw);
  return t.y * t.x / (real(2) * c * c * c);
}

// The outer rule's substitution u = C tan(phi): C = sqrt(1 + wn^2) for the
// rectangle's distance wn from the u axis, and the angles d1 <= 0 <= d2 of
// the ends [uc - fu, uc + fu] from phi_m = atan(uc / C), each from one
// arctangent difference (no subtraction of nearly equal angles). Returns
// vec3(C, d1, d2).
vec3 tanRuleFrame(real uc, real wc, real fu, real fw) {
  real C = sqrt(real(1) + sqr(intervalNear(wc, fw)));
  real d1 = -atan(fu * C, C * C + (uc - fu) * uc);
  real d2 = atan(fu * C, C * C + uc * (uc + fu));
  return vec3(C, d1, d2);
}

// The node at angle offset delta from phi_m, tau = tan(delta): vec2(u,
// du / dphi), written so that u - uc keeps full relative precision far from
// the origin.
vec2 tanRuleNode(real tau, real uc, real C) {
  real tm = uc / C;
  real u = uc + C * tau * (real(1) + tm * tm) / (real(1) - tm * tau);
  return vec2(u, (C * C + u * u) / C);
}

// One Gauss-Legendre node of the outer integral over u (tau as tanRuleNode).
real ggxRectOuterNode(real tau, real uc, real C, real wc, real fw) {
  vec2 n = tanRuleNode(tau, uc, C);
  return ggxRectInnerMean(sqrt(real(1) + n.x * n.x), wc, fw) * n.y;
}

// Whether the normalised rectangle is narrower in angle along w than along u
// (the direction the outer rule then integrates over): atan2(yW, xW) <
// atan2(yU, xU) for the widths' half-plane vectors (y >= 0), compared as a
// cross product of the vectors scaled to unit 1-norm (so the products stay
// finite in float), without the arctangents.
bool narrowerAlongW(real uc, real wc, real fu, real fw) {
  real Cu = sqrt(real(1) + sqr(intervalNear(wc, fw)));
  real Cw = sqrt(real(1) + sqr(intervalNear(uc, fu)));
  real yU = real(2) * fu * Cu;
  real xU = Cu * Cu + (uc - fu) * (uc + fu);
  real yW = real(2) * fw * Cw;
  real xW = Cw * Cw + (wc - fw) * (wc + fw);
  real nU = abs(xU) + yU;  // > 0: xU >= 1 where yU = 0
  real nW = abs(xW) + yW;
  return (xW / nW) * (yU / nU) > (yW / nW) * (xU / nU);
}

// dphi / du over [uc - fu, uc + fu] after u = C tan(phi), from the angles
// d1 <= 0 <= d2 of the ends (a sum of magnitudes: no cancellation); the
// limit C / (C^2 + uc^2) for a vanishing side.
real anglePerSlope(real d1, real d2, real uc, real fu, real C) {
  return fu > real(1e-12) ? (d2 - d1) / (real(2) * fu) : C / (C * C + uc * uc);
}

// vec2(node, weight) of node k = 0..n-1 of the n-point Gauss-Legendre rule
// on [-1, 1] (n = 4 or 8), the nodes in pairs -y, +y.
vec2 gaussLegendreNode(int n, int k) {
  vec2 pair = gaussLegendrePair(n, k / 2);
  return vec2((k - (k / 2) * 2) == 0 ? -pair.x : pair.x, pair.y);
}

// The mean over the normalised rectangle by the tangent rule, `pending` false
// for a pixel the tensor rule took. One node per loop pass: lavapipe runs
// every side of every branch for a SIMD batch (an if is a mask, not a jump),
// but stops a loop once no lane needs another pass, so a batch whose lanes
// all took the tensor rule pays one masked pass here, not 4 or 8.
real ggxRectMeanNormalized(real uc, real wc, real fu, real fw, bool pending) {
  uc = abs(uc);
  wc = abs(wc);
  if (narrowerAlongW(uc, wc, fu, fw)) {  // integrate numerically over the narrower direction
    real t = uc; uc = wc; wc = t;
    t = fu; fu = fw; fw = t;
  }
  vec3 frame = tanRuleFrame(uc, wc, fu, fw);
  real C = frame.x;
  real d1 = frame.y;
  real d2 = frame.z;
  real mid = real(0.5) * (d1 + d2);
  real half_ = real(0.5) * (d2 - d1);
  // Narrow in angle: 4-point Gauss-Legendre already meets the bound; else 8.
  int n = d2 - d1 < real(0.3) ? 4 : 8;
  real sum = real(0);
  for (int k = 0; k < (pending ? n : 0); ++k) {
    vec2 node = gaussLegendreNode(n, k);
    sum += node.y * ggxRectOuterNode(tan(mid + half_ * node.x), uc, C, wc, fw);
  }
  // mean = (1 / du) * (dphi / 2) * sum.
  return real(0.5) * anglePerSlope(d1, d2, uc, fu, C) * sum;
}

real ggxRectMeanStable(vec2 hpp, vec2 roughness, vec2 footprint) {
  vec2 a = clampAlpha(roughness);
  vec2 c = clampSlope(hpp);
  vec2 f = min(abs(footprint), vec2(SLOPE_MAX, SLOPE_MAX));
  real uc = abs(c.x / a.x), wc = abs(c.y / a.y), fu = f.x / a.x, fw = f.y / a.y;
  // Both rules run for every pixel (see ggxRectMeanNormalized); each costs a
  // masked pass where the other one holds.
  ivec2 points = tensorRulePoints(uc, wc, fu, fw, real(0), real(0), real(0));
  real tensor = tensorRuleMean(uc, wc, fu, fw, real(0), real(0), points);
  real tangent = ggxRectMeanNormalized(uc, wc, fu, fw, points.x == 0);
  return (points.x > 0 ? tensor : tangent) / (PI * a.x * a.y);
}

// ---------------------------------------------------------------------------
// Rectangle mean with the Jacobian inside (ours; "k16-ggx-rect-jacobian").
//
// Why: the pixel averages the solid-angle NDF D(h) = P22(s) / h.z^4 =
// P22(s) (1 + |s|^2)^2 over its footprint. Seed 000 (000_16155bfd1e3ea941.txt,
// "Convolving with GGX": `val / max(1e-3f, H.z*H.z*H.z*H.z)`) and
// k16-ggx-rect-stable average P22 alone and apply 1 / h.z^4 of the centre,
// which is right only while (1 + |s|^2)^2 is constant over the footprint. At
// silhouettes the centre's h.z is small while the footprint reaches the lobe,
// and the centre's Jacobian then multiplies the peak's P22.
//
// In normalised slopes (u, w) = (x / ax, y / ay), q = 1 + u^2 + w^2, and with
// m = min(ax^2, ay^2), M = max(ax^2, ay^2), e = M - m and u the normalised
// slope along the rougher axis:
//   1 + |s|^2 = 1 + ax^2 u^2 + ay^2 w^2 = m q + A,  A = 1 - m + e u^2,
//   pi ax ay P22(s) (1 + |s|^2)^2 = (m + A / q)^2 = m^2 + 2 m A / q + A^2 / q^2.
// For alpha <= 1 all three terms are non-negative, so nothing cancels, even
// though the integrand tends to a constant ((ax^2 u^2 + ay^2 w^2) / (u^2 + w^2))^2
// far from the lobe, where P22's |s|^-4 tail meets the Jacobian's |s|^4. At
// fixed u, A is a constant, so the inner integral over w needs only the means
// of 1 / q (an arctangent difference, the same dpsi as below) and of 1 / q^2
// (ggxRectInnerMean's closed form): the rougher axis is always the outer one
// (for isotropic roughness, the narrower in angle, as in the stable rect).
//
// The outer integral: footprints small against their distance from the
// lobe's poles take the tensor rule (above). The others cannot take the
// stable rect's tangent rule: 1 / q decays only like 1 / u^2 and the
// anisotropic part of A^2 / q^2 not at all, so after the tangent substitution
// they grow like sec(phi) and sec^2(phi) towards pi / 2 (the 8-point rule of
// the stable rect missed up to 47 % of the mean of 1 / q over a 1e4-alpha
// footprint). They take u = C sinh(xi) instead: profiles like 1 / u^2, 1 / u
// and 1 become e^-xi, 1 and e^xi, smooth on every scale between the lobe and
// the footprint, and an 8-point rule on panels at most XI_PANEL wide in xi
// integrates them (tuned on 20000 random rectangles, worst 5e-6 in double;
// 1.4e-4 at 3.5 wide).
//
// Bound: relative error <= 1e-4 in float32 against a double adaptive
// quadrature over the stable rect's grid (tests/shading/ggx_rect_test.cpp;
// measured 2.6e-6 there, 3.7e-6 over the 3000 random rectangles of
// GgxRectJacobian.RandomRectangles*, with slopes to 8 and anisotropy to
// 1000:1).
// Cost: the tensor rule's 16 to 64 divisions for most pixels; the others 8
// inner evaluations (one atan each, ggxRectInnerTerms) per panel, a panel per
// 2.5 in xi (a decade of footprint size over the lobe's, counted once for a
// footprint across the lobe: 24 for one 100 lobe widths across).
// docs/renderer.md has the measurements.

// Mean over w of (m + A / q)^2 - m^2 at outer coordinate u (see above).
real ggxRectJacobianRow(real u, real wc, real fw, real m, real e) {
  // The means over w of c^2 / q and c^4 / q^2 (ggxRectInnerTerms' r c and
  // B r c / 2): 1 / q and 1 / q^2 scaled so that both stay near 1 wherever
  // they matter and neither overflows nor underflows in float.
  real c2 = real(1) + u * u;
  real c = sqrt(c2);
  vec2 t = ggxRectInnerTerms(c, wc, fw);
  real k = (real(1) - m + e * u * u) / c2;  // A / c^2, bounded by max(1 - m, e)
  return k * t.x * c * (real(2) * m + real(0.5) * k * t.y);
}

// asinh(x) / x, finite at 0 (the series below 1e-3, as a select).
real asinhRatio(real x) {
  x = abs(x);
  return x < real(1e-3) ? real(1) - x * x / real(6) : asinh(x) / x;
}

// (asinh(b) - asinh(a)) / (b - a) for 0 <= a <= b, with d = b - a given
// exactly, finite and without cancellation for any gap, zero included:
// asinh(b) - asinh(a) = asinh(x) with
// x = b sqrt(1 + a^2) - a sqrt(1 + b^2) = d (b + a) / (b sqrt(1 + a^2) + a sqrt(1 + b^2)).
// (A footprint across u = 0, a < 0, is folded before it gets here.)
real asinhSlope(real a, real b, real d) {
  real den = b * sqrt(real(1) + a * a) + a * sqrt(real(1) + b * b);
  real ratio = b > real(0) ? (b + a) / den : real(1);  // b = 0: a = b = 0, the limit 1
  return asinhRatio(d * ratio) * ratio;
}

// Panel width in xi of the sinh rule's 8-point panels, and the panel cap.
const real XI_PANEL = real(2.5);
const int XI_PANELS_MAX = 32;

// Mean over the normalised rectangle of (m + A / q)^2 - m^2, u the outer
// axis, by the sinh rule; `pending` false for a pixel the tensor rule took.
// One node per loop pass, so that a SIMD batch pays for its widest lane's
// nodes and a batch the tensor rule took whole pays one masked pass
// (lavapipe runs every side of every branch; see ggxRectMeanNormalized).
// The footprint's extent in xi and the node positions come from asinhSlope,
// so a footprint narrow against its distance from the lobe (the tangent
// rule's case before the tensor rule took most of them) keeps its precision
// and no division by the half-side appears.
real ggxRectJacobianSinhMean(real uc, real wc, real fu, real fw, real m, real e, bool pending) {
  uc = abs(uc);  // the integrand is even in u and in w
  // The sinh scale: the lobe's C, or below it where A = 1 - m + e u^2 turns
  // from its constant to its quadratic part (u^2 = (1 - m) / e), which the
  // panels must resolve as well.
  real C = sqrt(real(1) + sqr(intervalNear(wc, fw)));
  if (e > real(0)) C = clamp(sqrt(max(real(1) - m, real(0)) / e), real(1), C);
  real a = (uc - fu) / C;
  real b = (uc + fu) / C;
  // The integrand is even in xi (u is odd, du / dxi even, the row even in u),
  // so a footprint across u = 0 folds: [0, min] counts twice and [min, max]
  // once, where min and max are the ends' distances asinh(|a|), asinh(b).
  // That halves the panels of a footprint centred on the lobe, the widest
  // case. Each segment's length over 2 fu (r1, r2) comes without a division
  // by fu: 2 fu / C = b - a exactly.
  real len1, len2, r1, r2, start1, weight1;
  if (a < real(0)) {
    real pa = -a * asinhRatio(a);  // asinh(|a|), precise for tiny |a| too
    real pb = b * asinhRatio(b);
    real D = C * (b - a);          // 2 fu, a sum of magnitudes
    len1 = min(pa, pb);
    len2 = max(pa, pb) - len1;
    r1 = len1 / D;
    r2 = len2 / D;
    start1 = real(0);
    weight1 = real(2);
  } else {
    real slope = asinhSlope(a, b, real(2) * fu / C);  // (xi(b) - xi(a)) / (b - a)
    len1 = real(2) * fu / C * slope;
    len2 = real(0);
    r1 = slope / C;
    r2 = real(0);
    start1 = asinh(a);
    weight1 = real(1);
  }
  int n1 = clamp(int(ceil(len1 / XI_PANEL)), 1, XI_PANELS_MAX);
  int n2 = len2 > real(0) ? clamp(int(ceil(len2 / XI_PANEL)), 1, XI_PANELS_MAX) : 0;
  real sum = real(0);
  for (int i = 0; i < (pending ? 8 * (n1 + n2) : 0); ++i) {
    int panel = i / 8;
    vec2 node = gaussLegendreNode(8, i - panel * 8);
    bool first = panel < n1;
    int n = first ? n1 : n2;
    real h = (first ? len1 : len2) / real(n);
    real xi = (first ? start1 : len1) + (real(first ? panel : panel - n1) + real(0.5) + real(0.5) * node.x) * h;
    // Segment weight times (its length / 2 fu) / (2 panels): the panel's
    // (h / 2) sum over 2 fu.
    real scale = (first ? weight1 * r1 : r2) / real(2 * n);
    real E = exp(xi);  // |xi| <= asinh(1e12 / C) < 29: finite in float
    real invE = real(1) / E;
    real u = real(0.5) * C * (E - invE);
    real dudxi = real(0.5) * C * (E + invE);
    sum += scale * node.y * ggxRectJacobianRow(u, wc, fw, m, e) * dudxi;
  }
  return sum;
}

// pi ax ay times the footprint mean of P22(s) (1 + |s|^2)^2, in normalised
// coordinates; ax2, ay2 the squared roughness. Both rules run for every
// pixel, each a masked pass where the other holds.
real ggxRectJacobianMeanNormalized(real uc, real wc, real fu, real fw, real ax2, real ay2) {
  uc = abs(uc);
  wc = abs(wc);
  real m = min(ax2, ay2);
  ivec2 points = tensorRulePoints(uc, wc, fu, fw, ax2 - m, ay2 - m, m);
  real tensor = tensorRuleMean(uc, wc, fu, fw, ax2, ay2, points);
  real e = abs(ax2 - ay2);
  bool swapAxes;
  if (e > real(0)) {
    swapAxes = ay2 > ax2;  // the rougher axis is the outer one (see above)
  } else {  // isotropic: integrate numerically over the narrower direction in angle
    swapAxes = narrowerAlongW(uc, wc, fu, fw);
  }
  if (swapAxes) {
    real t = uc; uc = wc; wc = t;
    t = fu; fu = fw; fw = t;
  }
  real sinhMean = m * m + ggxRectJacobianSinhMean(uc, wc, fu, fw, m, e, points.x == 0);
  // (1 + |s|^2) / q >= min(1, m) everywhere; for alpha > 1 (outside the
  // bound) the expansion cancels and only this keeps it meaningful.
  return points.x > 0 ? tensor : max(sinhMean, sqr(min(m, real(1))));
}

// Footprint mean of the solid-angle density D = P22(s) (1 + |s|^2)^2 over the
// rectangle [c - f, c + f]: the pixel's D(h) itself, no Jacobian to apply.
real ggxRectMeanJacobian(vec2 hpp, vec2 roughness, vec2 footprint) {
  vec2 a = clampAlpha(roughness);
  vec2 c = clampSlope(hpp);
  vec2 f = min(abs(footprint), vec2(SLOPE_MAX, SLOPE_MAX));
  real g = ggxRectJacobianMeanNormalized(c.x / a.x, c.y / a.y, f.x / a.x, f.y / a.y, a.x * a.x, a.y * a.y);
  return g / (PI * a.x * a.y);
}
