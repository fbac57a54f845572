// Spherical Gaussians of the shading core (shading/glsl/sg.glsl) seen
// from C++, compiled for float and double: the SG / ASG algebra and the GGX
// specular response to an SG light of seeds/004_ad807e344d5111d8.txt.
// sg.glsl says what each function approximates; docs/renderer.md has the
// measured errors.
#pragma once

#include <glm/glm.hpp>

namespace shimmer::shading {

// amplitude * exp(sharpness * (axis . d - 1)); axis unit.
template <class T>
struct Sg {
  glm::vec<3, T> axis{0, 0, 1};
  T sharpness = 1;
  glm::vec<3, T> amplitude{1, 1, 1};
};

// amplitude * max(d . basis_z, 0) * exp(-sharpness_x (d . basis_x)^2 - sharpness_y (d . basis_y)^2);
// orthonormal basis.
template <class T>
struct Asg {
  glm::vec<3, T> basis_x{1, 0, 0};
  glm::vec<3, T> basis_y{0, 1, 0};
  glm::vec<3, T> basis_z{0, 0, 1};
  T sharpness_x = 1;
  T sharpness_y = 1;
  glm::vec<3, T> amplitude{1, 1, 1};
};

template <class T>
glm::vec<3, T> SgEvaluate(const Sg<T>& sg, glm::vec<3, T> dir);
// Integral over the sphere (closed form).
template <class T>
glm::vec<3, T> SgIntegral(const Sg<T>& sg);
// Integral over the sphere of the product (closed form, overflow-free).
template <class T>
glm::vec<3, T> SgInnerProduct(const Sg<T>& a, const Sg<T>& b);
// -expm1(-y) / y, 1 at y = 0 (the helper the closed forms use).
template <class T>
T OneMinusExpNegOver(T y);

// The GGX NDF as an SG about `normal` (sharpness 2 / alpha^2, amplitude 1 / (pi alpha^2)).
template <class T>
Sg<T> DistributionTermSg(glm::vec<3, T> normal, T alpha);
// The NDF lobe moved to the light domain for `view` (Wang et al. 2009).
template <class T>
Sg<T> WarpDistributionSg(const Sg<T>& ndf, glm::vec<3, T> view);
// The same, anisotropic (Xu et al. 2013).
template <class T>
Asg<T> WarpDistributionAsg(const Sg<T>& ndf, glm::vec<3, T> view);
template <class T>
glm::vec<3, T> AsgEvaluate(const Asg<T>& asg, glm::vec<3, T> dir);
// Integral over the sphere of ASG x SG, Xu et al.'s planar approximation.
template <class T>
glm::vec<3, T> ConvolveAsgSg(const Asg<T>& asg, const Sg<T>& sg);

// Outgoing specular radiance towards `view`: int f_GGX(l, view) L(l) (n.l)+ dl
// for the SG light L, GGX roughness `alpha` (isotropic), Schlick F0 `f0`, as
// seed 004 approximates it with the SG warp or the ASG warp.
template <class T>
glm::vec<3, T> SpecularTermSgWarp(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view,
                                  glm::vec<3, T> f0);
template <class T>
glm::vec<3, T> SpecularTermAsgWarp(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view,
                                   glm::vec<3, T> f0);

// --- The exact integral against an SG light (sg_light.glsl) ----------------
// The renderer's GGX BRDF (D, height-correlated G2, Schlick F) on a surface
// whose shading and geometric normal is `normal`, variant none.

// One balance-heuristic estimate: a direction from the SG with u_light and a
// reflected GGX visible normal with u_brdf, both in [0, 1)^2 (the reference's
// per-sample estimator).
template <class T>
glm::vec<3, T> SgLightSpecularEstimate(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view,
                                       glm::vec<3, T> f0, glm::vec<2, T> u_light, glm::vec<2, T> u_brdf);
// The fixed quadrature 1-spp variants shade with.
template <class T>
glm::vec<3, T> SgLightSpecularQuadrature(const Sg<T>& light, glm::vec<3, T> normal, T alpha, glm::vec<3, T> view,
                                         glm::vec<3, T> f0);
// int L(l) (n.l)+ dl, converged, and its one-sample estimate from an SG direction (the reference's).
template <class T>
glm::vec<3, T> SgIrradiance(const Sg<T>& light, glm::vec<3, T> normal);
template <class T>
glm::vec<3, T> SgIrradianceEstimate(const Sg<T>& light, glm::vec<3, T> normal, glm::vec<2, T> u);
// The SG's own direction sampling and its density in solid angle.
template <class T>
glm::vec<3, T> SgSampleDirection(const Sg<T>& light, glm::vec<2, T> u);
template <class T>
T SgDirectionPdf(const Sg<T>& light, glm::vec<3, T> dir);

}  // namespace shimmer::shading
