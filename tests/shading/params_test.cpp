// The variant parameters' one table of valid ranges, and the messages of the
// validation that reads it (ValidateParam, ResolveParams).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "shading.h"

namespace shimmer::shading {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(ParamRanges, NameTheFourParametersOfVariantParams) {
  std::vector<std::string> names;
  std::vector<double Params<double>::*> members;
  for (const ParamRange& r : ParamRanges()) {
    names.emplace_back(r.name);
    for (auto m : members) EXPECT_NE(m, r.member) << r.name;
    members.push_back(r.member);
    EXPECT_EQ(FindParamRange(r.name), &r);
    EXPECT_TRUE(std::isfinite(r.lower) && std::isfinite(r.upper) && r.lower < r.upper) << r.name;
    EXPECT_FALSE(r.meaning.empty()) << r.name;
  }
  EXPECT_EQ(names, (std::vector<std::string>{"fp_max", "fp_min_cap", "sigma2", "kappa"}));
  EXPECT_EQ(members.size(), 4u);
  EXPECT_EQ(FindParamRange("alpha"), nullptr);
  // Each name reaches its own field.
  Params<double> p{1, 2, 3, 4};
  EXPECT_EQ(ParamValue(p, "fp_max"), 1);
  EXPECT_EQ(ParamValue(p, "fp_min_cap"), 2);
  EXPECT_EQ(ParamValue(p, "sigma2"), 3);
  EXPECT_EQ(ParamValue(p, "kappa"), 4);
}

TEST(ParamRanges, EveryCatalogueParameterIsInTheTableWithAValidDefault) {
  for (const VariantInfo& v : Variants())
    for (const ParamInfo& p : v.params) {
      ASSERT_NE(FindParamRange(p.name), nullptr) << v.name << " " << p.name;
      EXPECT_EQ(ValidateParam(p.name, p.default_value), "") << v.name;
      EXPECT_EQ(ParamValue(ResolveParams(v, {}).values, p.name), p.default_value) << v.name << " " << p.name;
    }
}

TEST(ValidateParam, AcceptsTheClosedRangeAndRejectsEverythingElse) {
  for (const ParamRange& r : ParamRanges()) {
    EXPECT_EQ(ValidateParam(r.name, r.upper), "") << r.name;
    EXPECT_EQ(ValidateParam(r.name, 0.5 * (r.lower + r.upper)), "") << r.name;
    EXPECT_EQ(ValidateParam(r.name, r.lower).empty(), r.lower_inclusive) << r.name;
    EXPECT_EQ(ValidateParam(r.name, std::nextafter(r.lower, kInf)), "") << r.name;
    for (double bad : {std::nextafter(r.lower, -kInf), std::nextafter(r.upper, kInf), -1.0, kInf, -kInf,
                       std::numeric_limits<double>::quiet_NaN(), 1e300})
      EXPECT_NE(ValidateParam(r.name, bad), "") << r.name << " " << bad;
  }
}

TEST(ValidateParam, MessageNamesTheParameterTheRangeAndTheValue) {
  EXPECT_EQ(ValidateParam("sigma2", std::nan("")), "parameter sigma2 must be >= 0 and <= 10000, got nan");
  EXPECT_EQ(ValidateParam("kappa", -kInf), "parameter kappa must be >= 0 and <= 10000, got -inf");
  EXPECT_EQ(ValidateParam("fp_max", -0.25), "parameter fp_max must be >= 0 and <= 10000, got -0.25");
  EXPECT_EQ(ValidateParam("fp_min_cap", 1e39), "parameter fp_min_cap must be >= 0 and <= 100, got 1e+39");
  EXPECT_EQ(ValidateParam("alpha", 1),
            "unknown parameter 'alpha' (the parameters are fp_max, fp_min_cap, sigma2, kappa)");
  for (const ParamRange& r : ParamRanges()) {
    const std::string m = ValidateParam(r.name, -1);
    EXPECT_EQ(m.find("0.000000"), std::string::npos) << m;
    EXPECT_NE(m.find(r.lower_inclusive ? ">= " : "> "), std::string::npos) << m;
  }
}

TEST(ResolveParams, RejectsWithTheTablesMessage) {
  const VariantInfo* tk19 = FindVariant("tk19");
  ASSERT_NE(tk19, nullptr);
  for (double bad : {std::nan(""), kInf, -1e-300, 2e4}) {
    const std::vector<std::pair<std::string, double>> o = {{"sigma2", bad}};
    const ResolvedParams r = ResolveParams(*tk19, o);
    EXPECT_EQ(r.error, ValidateParam("sigma2", bad));
    EXPECT_NE(r.error, "");
  }
  const std::vector<std::pair<std::string, double>> zero = {{"sigma2", 0}, {"kappa", 1e4}};
  const ResolvedParams ok = ResolveParams(*tk19, zero);
  EXPECT_EQ(ok.error, "");
  EXPECT_EQ(ok.values.sigma2, 0);
  EXPECT_EQ(ok.values.kappa, 1e4);
  const std::vector<std::pair<std::string, double>> foreign = {{"fp_max", 1}};
  EXPECT_NE(ResolveParams(*tk19, foreign).error.find("has no parameter 'fp_max'"), std::string::npos);
}

}  // namespace
}  // namespace shimmer::shading
