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
// footprints down to zero work.
//
// Bound: relative error <= 1e-4 in float32 against a 30-digit oracle over
// alpha 1e-3..1, half-sides 1e-6..10 (unequal too), centres up to 100 alpha
// and slopes up to 6 (tests assert 1e-3). Cost: 4 or 8 inner evaluations,
// each one atan and three sqrt (see ggxRectInnerTerms), and a polynomial
// (4 points) or a tan (8 points) per node.

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

// tan x for |x| < 0.3 (Taylor series to x^15; truncation below 1e-11
// relative). The narrow-angle rules' nodes lie within 0.3 of the footprint's
// centre angle, and a polynomial there costs a fraction of tan's range
// reduction and division.
real tanSmall(real x) {
  real x2 = x * x;
  return x + x * x2 * (real(1.0 / 3.0) +
                       x2 * (real(2.0 / 15.0) +
                             x2 * (real(17.0 / 315.0) +
                                   x2 * (real(62.0 / 2835.0) +
                                         x2 * (real(1382.0 / 155925.0) +
                                               x2 * (real(21844.0 / 6081075.0) +
                                                     x2 * real(929569.0 / 638512875.0)))))));
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

// One Gauss-Legendre node of the outer integral over u, at angle offset
// delta from phi_m = atan(uc / C), tau = tan(delta); written so that u - uc
// keeps full relative precision far from the origin.
real ggxRectOuterNode(real tau, real uc, real C, real wc, real fw) {
  real tm = uc / C;
  real u = uc + C * tau * (real(1) + tm * tm) / (real(1) - tm * tau);
  real c = sqrt(real(1) + u * u);
  real jacobian = (C * C + u * u) / C;  // du / dphi
  return ggxRectInnerMean(c, wc, fw) * jacobian;
}

// Distance from 0 to the interval [xc - f, xc + f] (0 when it contains 0).
real intervalNear(real xc, real f) { return max(abs(xc) - f, real(0)); }

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

real ggxRectMeanNormalized(real uc, real wc, real fu, real fw) {
  uc = abs(uc);
  wc = abs(wc);
  if (narrowerAlongW(uc, wc, fu, fw)) {  // integrate numerically over the narrower direction
    real t = uc; uc = wc; wc = t;
    t = fu; fu = fw; fw = t;
  }
  real C = sqrt(real(1) + sqr(intervalNear(wc, fw)));
  real d1 = -atan(fu * C, C * C + (uc - fu) * uc);
  real d2 = atan(fu * C, C * C + uc * (uc + fu));
  real mid = real(0.5) * (d1 + d2);
  real half_ = real(0.5) * (d2 - d1);
  real sum;
  if (d2 - d1 < real(0.3)) {
    // Narrow in angle (the common case: footprints smaller than the lobe):
    // 4-point Gauss-Legendre already meets the bound. Every node lies within
    // 0.3 of the centre angle (d1 <= 0 <= d2), where tanSmall holds.
    real y0 = real(0.3399810435848563), h0 = real(0.6521451548625461);
    real y1 = real(0.8611363115940526), h1 = real(0.3478548451374538);
    sum = h0 * (ggxRectOuterNode(tanSmall(mid - half_ * y0), uc, C, wc, fw) +
                ggxRectOuterNode(tanSmall(mid + half_ * y0), uc, C, wc, fw)) +
          h1 * (ggxRectOuterNode(tanSmall(mid - half_ * y1), uc, C, wc, fw) +
                ggxRectOuterNode(tanSmall(mid + half_ * y1), uc, C, wc, fw));
  } else {
    // 8-point Gauss-Legendre nodes and weights on [-1, 1].
    real x0 = real(0.1834346424956498), g0 = real(0.3626837833783620);
    real x1 = real(0.5255324099163290), g1 = real(0.3137066458778873);
    real x2 = real(0.7966664774136267), g2 = real(0.2223810344533745);
    real x3 = real(0.9602898564975363), g3 = real(0.1012285362903763);
    sum = g0 * (ggxRectOuterNode(tan(mid - half_ * x0), uc, C, wc, fw) +
                ggxRectOuterNode(tan(mid + half_ * x0), uc, C, wc, fw)) +
          g1 * (ggxRectOuterNode(tan(mid - half_ * x1), uc, C, wc, fw) +
                ggxRectOuterNode(tan(mid + half_ * x1), uc, C, wc, fw)) +
          g2 * (ggxRectOuterNode(tan(mid - half_ * x2), uc, C, wc, fw) +
                ggxRectOuterNode(tan(mid + half_ * x2), uc, C, wc, fw)) +
          g3 * (ggxRectOuterNode(tan(mid - half_ * x3), uc, C, wc, fw) +
                ggxRectOuterNode(tan(mid + half_ * x3), uc, C, wc, fw));
  }
  // mean = (1 / du) * (dphi / 2) * sum.
  return real(0.5) * anglePerSlope(d1, d2, uc, fu, C) * sum;
}

real ggxRectMeanStable(vec2 hpp, vec2 roughness, vec2 footprint) {
  vec2 a = clampAlpha(roughness);
  vec2 c = clampSlope(hpp);
  vec2 f = min(abs(footprint), vec2(SLOPE_MAX, SLOPE_MAX));
  real m = ggxRectMeanNormalized(c.x / a.x, c.y / a.y, f.x / a.x, f.y / a.y);
  return m / (PI * a.x * a.y);
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
// The outer integral: a footprint narrow in angle and away from the
// substitution's pole (width < 0.3 rad, and at least TAN_POLE_WIDTHS widths
// from pi / 2) uses the stable rect's 4-point rule after u = C tan(phi). Other
// footprints cannot: 1 / q decays only like 1 / u^2 and the anisotropic part
// of A^2 / q^2 not at all, so after the tangent substitution they grow like
// sec(phi) and sec^2(phi) towards pi / 2 (the 8-point rule of the stable rect
// missed up to 47 % of the mean of 1 / q over a 1e4-alpha footprint). There
// u = C sinh(xi) instead: profiles like 1 / u^2, 1 / u and 1 become e^-xi, 1
// and e^xi, smooth on every scale between the lobe and the footprint, and an
// 8-point rule on panels at most XI_PANEL wide in xi integrates them (both
// constants tuned on 20000 random rectangles, worst 5e-6 in double).
//
// Bound: relative error <= 1e-4 in float32 against a double adaptive
// quadrature over the stable rect's grid (tests/shading/ggx_rect_test.cpp;
// measured 4.8e-7 there, 4.8e-6 over the 3000 random rectangles of
// GgxRectJacobian.RandomRectangles*, with slopes to 8 and anisotropy to
// 1000:1).
// Cost: 4 inner evaluations (one atan each, ggxRectInnerTerms) for narrow
// footprints; wide ones take 8 per panel, a panel per decade of footprint size
// over the lobe's on each side of it (64 for a footprint 1e4 lobe widths
// across). docs/renderer.md has the measurements.

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

// One node of the outer rule at t: the tangent substitution u = uc + C tan-offset
// (t an angle offset from phi_m = atan(uc / C), as ggxRectOuterNode) or the
// sinh substitution u = C sinh(t); returns the row times du / dt. Both sides
// are cheap: lavapipe runs both for a SIMD batch whose lanes disagree.
real ggxRectJacobianNode(bool tanRule, real t, real uc, real C, real wc, real fw, real m, real e) {
  real u;
  real dudt;
  if (tanRule) {
    real tm = uc / C;
    real tau = tanSmall(t);
    u = uc + C * tau * (real(1) + tm * tm) / (real(1) - tm * tau);
    dudt = (C * C + u * u) / C;
  } else {
    real E = exp(t);  // |t| <= asinh(1e12 / C) < 29: finite in float
    real invE = real(1) / E;
    u = real(0.5) * C * (E - invE);
    dudt = real(0.5) * C * (E + invE);
  }
  return ggxRectJacobianRow(u, wc, fw, m, e) * dudt;
}

// Panel width in xi of the sinh rule's 8-point panels, the tangent rule's
// pole margin, and the panel cap.
const real XI_PANEL = real(2.5);
const real TAN_POLE_WIDTHS = real(2);
const int XI_PANELS_MAX = 32;

// Mean over the normalised rectangle of (m + A / q)^2 - m^2, u the outer axis.
// Both rules run in one loop of 4 nodes per pass: the tangent rule's 4-point
// panel in one pass, each 8-point panel of the sinh rule in two (its inner
// and outer node pairs). A SIMD batch of narrow footprints, the common case,
// then pays 4 rows and nothing for the wide footprints' rule: lavapipe runs
// every branch of a batch, and the sinh rule written out beside the tangent
// rule cost more than the rule the batch took (measured on sphere-field:
// 1.35x none with the sinh rule present but never taken, 1.16x without it).
real ggxRectJacobianOuterMean(real uc, real wc, real fu, real fw, real m, real e) {
  uc = abs(uc);  // the integrand is even in u and in w
  real C = sqrt(real(1) + sqr(intervalNear(wc, fw)));
  real d1 = -atan(fu * C, C * C + (uc - fu) * uc);
  real d2 = atan(fu * C, C * C + uc * (uc + fu));
  // atan(C, uc + fu): the far end's angular distance from the pole at pi / 2.
  bool tanRule = d2 - d1 < real(0.3) && atan(C, uc + fu) > TAN_POLE_WIDTHS * (d2 - d1);
  real start = d1;
  real h = d2 - d1;
  real scale;  // the rule's weighted sum times this is the mean
  int passes = 1;
  if (tanRule) {
    // Every node lies within 0.3 of phi_m (d1 <= 0 <= d2), where tanSmall holds.
    scale = real(0.5) * anglePerSlope(d1, d2, uc, fu, C);
  } else {
    // The sinh scale: the lobe's C, or below it where A = 1 - m + e u^2 turns
    // from its constant to its quadratic part (u^2 = (1 - m) / e), which the
    // panels must resolve as well.
    if (e > real(0)) C = clamp(sqrt(max(real(1) - m, real(0)) / e), real(1), C);
    start = asinh((uc - fu) / C);
    real xi2 = asinh((uc + fu) / C);
    int panels = clamp(int(ceil((xi2 - start) / XI_PANEL)), 1, XI_PANELS_MAX);
    h = (xi2 - start) / real(panels);
    scale = real(0.25) * h / fu;
    passes = 2 * panels;
  }
  real half_ = real(0.5) * h;
  real sum = real(0);
  for (int i = 0; i < passes; ++i) {
    // Gauss-Legendre nodes and weights on [-1, 1]: 4 points, or the inner
    // (even pass) and outer (odd pass) pairs of 8 points.
    bool outerPair = (i - (i / 2) * 2) == 1;
    real ya = tanRule ? real(0.3399810435848563) : (outerPair ? real(0.7966664774136267) : real(0.1834346424956498));
    real wa = tanRule ? real(0.6521451548625461) : (outerPair ? real(0.2223810344533745) : real(0.3626837833783620));
    real yb = tanRule ? real(0.8611363115940526) : (outerPair ? real(0.9602898564975363) : real(0.5255324099163290));
    real wb = tanRule ? real(0.3478548451374538) : (outerPair ? real(0.1012285362903763) : real(0.3137066458778873));
    real mid = tanRule ? real(0.5) * (d1 + d2) : start + (real(i / 2) + real(0.5)) * h;
    sum += wa * (ggxRectJacobianNode(tanRule, mid - half_ * ya, uc, C, wc, fw, m, e) +
                 ggxRectJacobianNode(tanRule, mid + half_ * ya, uc, C, wc, fw, m, e)) +
           wb * (ggxRectJacobianNode(tanRule, mid - half_ * yb, uc, C, wc, fw, m, e) +
                 ggxRectJacobianNode(tanRule, mid + half_ * yb, uc, C, wc, fw, m, e));
  }
  return scale * sum;
}

// pi ax ay times the footprint mean of P22(s) (1 + |s|^2)^2, in normalised
// coordinates; ax2, ay2 the squared roughness.
real ggxRectJacobianMeanNormalized(real uc, real wc, real fu, real fw, real ax2, real ay2) {
  uc = abs(uc);
  wc = abs(wc);
  real m = min(ax2, ay2);
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
  real mean = m * m + ggxRectJacobianOuterMean(uc, wc, fu, fw, m, e);
  // (1 + |s|^2) / q >= min(1, m) everywhere; for alpha > 1 (outside the
  // bound) the expansion cancels and only this keeps it meaningful.
  return max(mean, sqr(min(m, real(1))));
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
