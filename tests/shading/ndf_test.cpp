#include <gtest/gtest.h>

#include <cmath>

#include "shimmer/renderer/shading.h"

namespace shimmer::shading {
TEST(Catalogue, IdsMatchGlslConstants) { EXPECT_TRUE(CatalogueMatchesGlsl()); }
}  // namespace shimmer::shading

namespace shimmer::shading {
// Blinn-Phong as seed 003 writes it: D = (s + 2) / (2 pi) (n.h)^s, and P22 =
// D (n.h)^4, with s = 2 / alpha^2 - 2; near the lobe it is Beckmann's shape.
TEST(BlinnPhong, SlopeDensityIsTheSeedsNormalisedPowerLobe) {
  for (double power : {0.0, 2.0, 30.0, 100.0, 1000.0, 1e5}) {
    const double a = BlinnPhongAlpha(power);
    EXPECT_NEAR(BlinnPhongPower(a), power, 1e-9 * (1 + power));
    for (double r : {0.0, 0.001, 0.03, 0.2, 1.0, 5.0}) {
      const glm::dvec2 s{r * 0.6, r * 0.8};
      const double cos_t = 1 / std::sqrt(1 + r * r);
      const double want = (power + 2) / (2 * 3.14159265358979323846) * std::pow(cos_t, power + 4);
      const double got = SlopeDensity<double>(Ndf::kBlinnPhong, s, {a, a});
      EXPECT_NEAR(got, want, 1e-9 * want + 1e-300) << power << " " << r;
      const float gf = SlopeDensity<float>(Ndf::kBlinnPhong, glm::vec2(s), glm::vec2(float(a)));
      EXPECT_NEAR(gf, want, 2e-4 * want + 1e-30) << power << " " << r;
    }
  }
  // Sharp lobes approach Beckmann of the same alpha at the centre.
  const double a = 0.01;
  EXPECT_NEAR(SlopeDensity<double>(Ndf::kBlinnPhong, {0.005, 0}, {a, a}) /
                  SlopeDensity<double>(Ndf::kBeckmann, {0.005, 0}, {a, a}),
              1, 1e-3);
}
}  // namespace shimmer::shading
