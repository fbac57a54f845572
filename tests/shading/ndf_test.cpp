#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>

#include "shimmer/shading/shading.h"

namespace shimmer::shading {
// The GLSL constants the kernels dispatch on and the C++ catalogue are
// generated from one table (shading/variant_table.json): every entry's id is
// its constant's value in the GLSL the kernels compile, and every constant
// names an entry.
TEST(Catalogue, IdsMatchTheGeneratedGlslConstants) {
  std::string_view glsl;
  for (const auto& [file, text] : GlslSources())
    if (file == "variant_table.glsl") glsl = text;
  ASSERT_FALSE(glsl.empty()) << "variant_table.glsl is not among the embedded GLSL sources";
  std::map<std::string, int> value;  // catalogue name -> VARIANT_* or NMF_* value
  int stride = 0;
  std::istringstream in{std::string(glsl)};
  for (std::string line; std::getline(in, line);) {
    char constant[64], name[64];
    int v = 0;
    if (std::sscanf(line.c_str(), "const int %63s = %d;  // %63s", constant, &v, name) == 3 &&
        std::string(constant) != "NMF_NONE")
      value[name] = v;
    if (std::sscanf(line.c_str(), "const int NMF_STRIDE = %d;", &v) == 1) stride = v;
  }
  EXPECT_EQ(stride, kNormalMapFilterStride);
  ASSERT_EQ(value.size(), Variants().size());
  for (const VariantInfo& info : Variants()) {
    ASSERT_TRUE(value.count(std::string(info.name))) << info.name;
    const int v = value[std::string(info.name)];
    EXPECT_EQ(info.id, FiltersNormalMap(info) ? v * kNormalMapFilterStride : v) << info.name;
  }
  // The geometric filters fit below the stride.
  for (const VariantInfo& info : Variants()) {
    if (!FiltersNormalMap(info)) {
      EXPECT_LT(info.id, kNormalMapFilterStride) << info.name;
    }
  }
}

// The defaults of Params are the table's; each entry's defaults are
// accepted by its own parameters' ranges.
TEST(Catalogue, DefaultsLieInTheirRanges) {
  const Params<double> defaults;
  for (const ParamField& f : ParamFields()) EXPECT_TRUE(ValidateParam(f.name, defaults.*(f.member))) << f.name;
  for (const VariantInfo& info : Variants())
    for (const ParamInfo& p : info.params) EXPECT_TRUE(ValidateParam(p.name, p.default_value)) << info.name;
  // The packing follows ParamFields' order.
  Params<double> p;
  int i = 0;
  for (const ParamField& f : ParamFields()) p.*(f.member) = 0.5 + i++;
  const auto slots = PackVariantParams(p);
  for (int k = 0; k < kVariantParamCount; ++k) EXPECT_EQ(slots[k], 0.5f + k) << ParamFields()[k].name;
}
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
