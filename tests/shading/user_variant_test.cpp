// User variant files: the shimmer-param declarations, their errors (file and
// line), parameter resolution against the declared ranges, and the generated
// UserParams GLSL compiling into the kernel with the user's names.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "shimmer/shading/user_variant.h"
#include "shimmer/shading/spirv_compiler.h"

namespace shimmer::shading {
namespace {

const char* const kTwoParams =
    "// shimmer-variant: widens alpha by k\n"
    "// shimmer-param: k = 0.5 in [0, 4]: how much\n"
    "//   shimmer-param:   sigma2=0.25 in [0,1]\n"
    "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {\n"
    "  vec2 a = clampAlpha(alpha);\n"
    "  vec2 a2 = a * a + vec2(p.k * p.sigma2, p.k * p.sigma2);\n"
    "  return widenedNdf(ndf, clampSlope(f.hpp), vec2(sat(a2.x), sat(a2.y)));\n"
    "}\n";

TEST(UserVariant, DeclarationsGiveNamesDefaultsRangesAndSlots) {
  auto v = ParseUserVariant(kTwoParams, "mine.glsl");
  ASSERT_TRUE(v.ok()) << v.error();
  EXPECT_TRUE(v->declared);
  EXPECT_EQ(v->summary, "widens alpha by k");
  ASSERT_EQ(v->params.size(), 2u);
  EXPECT_EQ(v->params[0].name, "k");
  EXPECT_EQ(v->params[0].default_value, 0.5);
  EXPECT_EQ(v->params[0].lo, 0);
  EXPECT_EQ(v->params[0].hi, 4);
  EXPECT_EQ(v->params[0].meaning, "how much");
  EXPECT_EQ(v->params[0].line, 2);
  EXPECT_EQ(v->params[1].name, "sigma2");
  EXPECT_EQ(v->params[1].meaning, "");
  // A built-in name keeps its own slot; the other takes the first free one.
  EXPECT_EQ(v->params[1].slot, FindParamField("sigma2"));
  EXPECT_EQ(v->params[0].slot, FindParamField("fp_max"));
  EXPECT_EQ(v->content_hash.size(), 16u);
  auto edited = ParseUserVariant(std::string(kTwoParams) + "\n", "mine.glsl");
  EXPECT_NE(edited->content_hash, v->content_hash);
}

TEST(UserVariant, WithoutDeclarationsTheBuiltInParametersAreImplied) {
  auto v = ParseUserVariant("FilteredNdf userVariant(...) {}\n", "old.glsl");
  ASSERT_TRUE(v.ok());
  EXPECT_FALSE(v->declared);
  ASSERT_EQ(v->params.size(), ParamFields().size());
  for (std::size_t i = 0; i < ParamFields().size(); ++i) {
    EXPECT_EQ(v->params[i].name, ParamFields()[i].name);
    EXPECT_EQ(v->params[i].slot, &ParamFields()[i]);
    EXPECT_EQ(v->params[i].default_value, Params<double>{}.*(ParamFields()[i].member));
  }
  auto none = ParseUserVariant("// shimmer-params: none\n", "none.glsl");
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->declared);
  EXPECT_TRUE(none->params.empty());
}

TEST(UserVariant, BadDeclarationsNameTheFileAndLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"// shimmer-param: k 0.5 in [0, 1]", "k needs '= DEFAULT'"},
      {"// shimmer-param: = 0.5 in [0, 1]", "no parameter name"},
      {"// shimmer-param: k = 0.5", "needs its range"},
      {"// shimmer-param: k = 0.5 in [0 1]", "needs its range"},
      {"// shimmer-param: k = 2 in [0, 1]", "the default 2 lies outside [0, 1]"},
      {"// shimmer-param: k = 0 in [1, 0]", "is empty"},
      {"// shimmer-param: k = nan in [0, 1]", "not a finite number"},
      {"// shimmer-param: k = 0 in [0, 1e40]", "not a finite number"},
      {"// shimmer-param: float = 0 in [0, 1]", "'float' is not a usable parameter name"},
      {"// shimmer-param: gl_x = 0 in [0, 1]", "'gl_x' is not a usable parameter name"},
      {"// shimmer-param: k = 0 in [0, 1] what", "unexpected 'what' after the range"},
      {"// shimmer-param: k = 0 in [0, 1]\n// shimmer-param: k = 1 in [0, 1]", "k is declared twice"},
      {"// shimmer-params: some", "expected 'shimmer-params: none'"},
      {"// shimmer-variant: a\n// shimmer-variant: b", "a second shimmer-variant line"},
      {"// shimmer-param: a = 0 in [0, 1]\n// shimmer-param: b = 0 in [0, 1]\n// shimmer-param: c = 0 in [0, 1]\n"
       "// shimmer-param: d = 0 in [0, 1]\n// shimmer-param: e = 0 in [0, 1]\n// shimmer-param: f = 0 in [0, 1]\n"
       "// shimmer-param: g = 0 in [0, 1]\n// shimmer-param: h = 0 in [0, 1]\n// shimmer-param: i = 0 in [0, 1]",
       "more than 8 parameters"},
  };
  for (const auto& [text, problem] : cases) {
    auto v = ParseUserVariant("// my filter\n" + text + "\n", "bad.glsl");
    ASSERT_FALSE(v.ok()) << text;
    EXPECT_EQ(v.error().rfind("bad.glsl:", 0), 0u) << v.error();
    EXPECT_NE(v.error().find(problem), std::string::npos) << v.error();
    const int lines = 1 + int(std::count(text.begin(), text.end(), '\n'));
    EXPECT_NE(v.error().find("bad.glsl:" + std::to_string(1 + lines) + ":"), std::string::npos) << v.error();
  }
  auto both = ParseUserVariant("// shimmer-params: none\n// shimmer-param: k = 0 in [0, 1]\n", "both.glsl");
  ASSERT_FALSE(both.ok());
  EXPECT_NE(both.error().find("both.glsl:1:"), std::string::npos) << both.error();
}

TEST(UserVariant, ParametersResolveAgainstTheDeclaredRanges) {
  auto v = *ParseUserVariant(kTwoParams, "mine.glsl");
  auto defaults = ResolveUserParams(v, {});
  ASSERT_TRUE(defaults.ok());
  EXPECT_EQ(defaults->values.fp_max, 0.5);  // k's slot
  EXPECT_EQ(defaults->values.sigma2, 0.25);
  EXPECT_EQ(defaults->shown, (std::vector<std::pair<std::string, double>>{{"k", 0.5}, {"sigma2", 0.25}}));
  const std::vector<std::pair<std::string, double>> set = {{"k", 3}};
  auto three = ResolveUserParams(v, set);
  ASSERT_TRUE(three.ok());
  EXPECT_EQ(three->values.fp_max, 3);
  EXPECT_EQ(three->shown[0].second, 3);
  for (double bad : {-0.1, 4.5, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const std::vector<std::pair<std::string, double>> o = {{"k", bad}};
    auto r = ResolveUserParams(v, o);
    ASSERT_FALSE(r.ok()) << bad;
    EXPECT_NE(r.error().find("parameter k of mine.glsl must be >= 0 and <= 4"), std::string::npos) << r.error();
  }
  const std::vector<std::pair<std::string, double>> unknown = {{"kappa", 0.1}};
  auto r = ResolveUserParams(v, unknown);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("mine.glsl has no parameter 'kappa' (it declares: k, sigma2)"), std::string::npos)
      << r.error();
}

TEST(UserVariant, DescriptionListsEveryParameter) {
  const std::string d = DescribeUserVariant(*ParseUserVariant(kTwoParams, "mine.glsl"));
  EXPECT_NE(d.find("mine.glsl: widens alpha by k"), std::string::npos) << d;
  EXPECT_NE(d.find("k = 0.5 in [0, 4]: how much"), std::string::npos) << d;
  EXPECT_NE(d.find("sigma2 = 0.25 in [0, 1]"), std::string::npos) << d;
}

std::string ReadSource(const std::string& relative) {
  std::ifstream in(std::filesystem::path(SHIMMER_SOURCE_DIR) / relative);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The kernel as pipeline_cache.cpp builds it for a user file, with the
// file's own parameter names in UserParams.
TEST(UserVariant, GeneratedParamsCompileIntoTheKernel) {
  std::vector<GlslFile> extra;
  for (const auto& [name, text] : GlslSources()) extra.push_back({std::string(name), std::string(text)});
  extra.push_back({"channels.glsl", ReadSource("renderer/shaders/channels.glsl")});
  GlslFile kernel{"render.comp", ReadSource("renderer/shaders/render.comp")};
  kernel.text.insert(kernel.text.find('\n') + 1, "#define SHIMMER_USER_VARIANT\n#line 2\n");
  const std::string post =
      "// shimmer-param: strength = 2 in [0, 8]\n"
      "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {\n"
      "  return evalVariant(VARIANT_TK19, ndf, alpha * p.strength, f, variantParams(p));\n"
      "}\n";
  for (const std::string& text : {std::string(kTwoParams), post, std::string("// shimmer-params: none\n") +
                                                                    "FilteredNdf userVariant(int ndf, vec2 alpha, "
                                                                    "ShadingFootprint f, UserParams p) {\n"
                                                                    "  return widenedNdf(ndf, f.hpp, alpha * alpha);\n"
                                                                    "}\n"}) {
    const UserVariant v = *ParseUserVariant(text, "mine.glsl");
    std::vector<GlslFile> files = extra;
    files.push_back({"user_params.glsl", UserParamsGlsl(v)});
    files.push_back({"user_variant.glsl", text});
    auto spirv = CompileCompute(kernel, files);
    EXPECT_TRUE(spirv.ok()) << text << "\n" << UserParamsGlsl(v) << "\n" << spirv.error();
  }
}

TEST(UserVariant, LoadNamesAMissingFile) {
  auto v = LoadUserVariant("/nonexistent/mine.glsl");
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.error(), "/nonexistent/mine.glsl: no such variant file");
}

}  // namespace
}  // namespace shimmer::shading
