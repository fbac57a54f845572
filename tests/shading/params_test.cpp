// The variant parameters' one table of valid ranges, and the messages of the
// validation that reads it (ValidateParam, ResolveParams).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "shimmer/shading/shading.h"

namespace shimmer::shading {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(ParamFields, NameTheFiveParametersOfVariantParams) {
  std::vector<std::string> names;
  std::vector<double Params<double>::*> members;
  for (const ParamField& r : ParamFields()) {
    names.emplace_back(r.name);
    for (auto m : members) EXPECT_NE(m, r.member) << r.name;
    members.push_back(r.member);
    EXPECT_EQ(FindParamField(r.name), &r);
    EXPECT_TRUE(std::isfinite(r.lo) && std::isfinite(r.hi) && r.lo < r.hi) << r.name;
    EXPECT_FALSE(r.meaning.empty()) << r.name;
  }
  EXPECT_EQ(names, (std::vector<std::string>{"fp_max", "fp_min_cap", "sigma2", "kappa", "nm_scale", "curvature_scale",
                                              "curvature_bias", "curvature_exponent"}));
  EXPECT_EQ(members.size(), 8u);
  EXPECT_EQ(FindParamField("alpha"), nullptr);
  // Each name reaches its own field.
  Params<double> p{1, 2, 3, 4};
  EXPECT_EQ(ParamValue(p, "fp_max"), 1);
  EXPECT_EQ(ParamValue(p, "fp_min_cap"), 2);
  EXPECT_EQ(ParamValue(p, "sigma2"), 3);
  EXPECT_EQ(ParamValue(p, "kappa"), 4);
}

TEST(ParamFields, EveryCatalogueParameterIsInTheTableWithAValidDefault) {
  for (const VariantInfo& v : Variants())
    for (const ParamInfo& p : v.params) {
      ASSERT_NE(FindParamField(p.name), nullptr) << v.name << " " << p.name;
      EXPECT_TRUE(ValidateParam(p.name, p.default_value).ok()) << v.name;
      EXPECT_EQ(ParamValue(ResolveParams(v, {}).value(), p.name), p.default_value) << v.name << " " << p.name;
    }
}

TEST(ValidateParam, AcceptsTheClosedRangeAndRejectsEverythingElse) {
  for (const ParamField& r : ParamFields()) {
    EXPECT_TRUE(ValidateParam(r.name, r.hi).ok()) << r.name;
    EXPECT_TRUE(ValidateParam(r.name, 0.5 * (r.lo + r.hi)).ok()) << r.name;
    EXPECT_EQ(ValidateParam(r.name, r.lo).ok(), true) << r.name;
    EXPECT_TRUE(ValidateParam(r.name, std::nextafter(r.lo, kInf)).ok()) << r.name;
    for (double bad : {std::nextafter(r.lo, -kInf), std::nextafter(r.hi, kInf), r.lo - 1, kInf, -kInf,
                       std::numeric_limits<double>::quiet_NaN(), 1e300})
      EXPECT_FALSE(ValidateParam(r.name, bad).ok()) << r.name << " " << bad;
  }
}

TEST(ValidateParam, MessageNamesTheParameterTheRangeAndTheValue) {
  EXPECT_EQ(ValidateParam("sigma2", std::nan("")).error(), "parameter sigma2 must be >= 0 and <= 10000, got nan");
  EXPECT_EQ(ValidateParam("kappa", -kInf).error(), "parameter kappa must be >= 0 and <= 10000, got -inf");
  EXPECT_EQ(ValidateParam("fp_max", -0.25).error(), "parameter fp_max must be >= 0 and <= 10000, got -0.25");
  EXPECT_EQ(ValidateParam("fp_min_cap", 1e39).error(), "parameter fp_min_cap must be >= 0 and <= 100, got 1e+39");
  EXPECT_EQ(ValidateParam("alpha", 1).error(),
            "unknown parameter 'alpha' (the parameters are fp_max, fp_min_cap, sigma2, kappa, nm_scale, "
            "curvature_scale, curvature_bias, curvature_exponent)");
  EXPECT_EQ(ValidateParam("curvature_bias", -1.5).error(), "parameter curvature_bias must be >= -1 and <= 1, got -1.5");
  for (const ParamField& r : ParamFields()) {
    const std::string m = ValidateParam(r.name, r.lo - 1).error();
    EXPECT_EQ(m.find("0.000000"), std::string::npos) << m;
    EXPECT_NE(m.find(">= "), std::string::npos) << m;
  }
}

TEST(ResolveParams, RejectsWithTheTablesMessage) {
  const VariantInfo* tk19 = FindVariant("tk19");
  ASSERT_NE(tk19, nullptr);
  for (double bad : {std::nan(""), kInf, -1e-300, 2e4}) {
    const std::vector<std::pair<std::string, double>> o = {{"sigma2", bad}};
    const auto r = ResolveParams(*tk19, o);
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error(), ValidateParam("sigma2", bad).error());
  }
  const std::vector<std::pair<std::string, double>> zero = {{"sigma2", 0}, {"kappa", 1e4}};
  const auto ok = ResolveParams(*tk19, zero);
  ASSERT_TRUE(ok) << ok.error();
  EXPECT_EQ(ok->sigma2, 0);
  EXPECT_EQ(ok->kappa, 1e4);
  const std::vector<std::pair<std::string, double>> foreign = {{"fp_max", 1}};
  EXPECT_NE(ResolveParams(*tk19, foreign).error().find("has no parameter 'fp_max'"), std::string::npos);
}

}  // namespace
}  // namespace shimmer::shading
