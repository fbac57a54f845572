// User variant files in specs: the {"file", "name", "params"} entry, its
// errors (the spec's line, the file's line), and job ids that hash the
// file's content and its declared defaults but not where it lies.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "shimmer/experiments/job.h"
#include "shimmer/experiments/spec.h"

namespace shimmer::experiments {
namespace {

namespace fs = std::filesystem;

const char* const kMine =
    "// shimmer-variant: widens alpha by k\n"
    "// shimmer-param: k = 0.5 in [0, 4]: how much\n"
    "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {\n"
    "  vec2 a = clampAlpha(alpha);\n"
    "  vec2 a2 = a * a + vec2(p.k, p.k) * normalSpread(f.dn_dx, f.dn_dy);\n"
    "  return widenedNdf(ndf, clampSlope(f.hpp), vec2(sat(a2.x), sat(a2.y)));\n"
    "}\n";

struct Folder {
  fs::path dir = fs::temp_directory_path() /
                 ("shimmer-userspec-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  Folder() {
    fs::remove_all(dir);
    fs::create_directories(dir / "specs");
  }
  ~Folder() { fs::remove_all(dir); }
  void Write(const std::string& name, const std::string& text) const { std::ofstream(dir / name) << text; }
  // A spec in specs/ with the given variants entry; files are looked for
  // from specs/.
  Result<Spec> Parse(const std::string& variants) const {
    const std::string text = R"({"name": "u", "scenes": ["sphere"], "materials": ["ggx:0.1"], "cameras": ["orbit"],
  "variants": )" + variants + R"(, "size": [16, 16], "frames": 2})";
    return ParseSpec(text, (dir / "specs" / "u.json").string());
  }
};

TEST(UserVariantSpec, AFileEntryExpandsToJobsWithTheFileAndEveryDeclaredParameter) {
  Folder f;
  f.Write("mine.glsl", kMine);
  auto spec = f.Parse(R"(["none", {"file": "../mine.glsl", "name": "mine", "params": {"k": [0.25, 1]}}])");
  ASSERT_TRUE(spec.ok()) << spec.error();
  ASSERT_EQ(spec->user_variants.count("mine"), 1u);
  const shading::UserVariant& ref = *spec->user_variants.at("mine");
  EXPECT_EQ(ref.file, (f.dir / "specs" / ".." / "mine.glsl").lexically_normal().string());
  EXPECT_EQ(ref.summary, "widens alpha by k");
  ASSERT_NE(shading::FindUserParam(ref, "k"), nullptr);
  EXPECT_EQ(shading::FindUserParam(ref, "k")->default_value, 0.5);
  const std::vector<Job> jobs = ExpandJobs(*spec);
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[1].variant, "mine");
  EXPECT_EQ(jobs[1].params.at("k"), 0.25);
  EXPECT_EQ(jobs[2].params.at("k"), 1);
  EXPECT_EQ(jobs[1].variant_file, ref.file);
  EXPECT_EQ(jobs[1].variant_hash, ref.content_hash);
  EXPECT_TRUE(ReadsDerivatives(jobs[1].variant));
  EXPECT_TRUE(jobs[0].variant_hash.empty());
  // The job round-trips through the store's JSON with its file.
  const Job back = Job::FromJson(jobs[1].ToJson());
  EXPECT_EQ(back.variant_file, ref.file);
  EXPECT_EQ(JobId(back), JobId(jobs[1]));
}

TEST(UserVariantSpec, IdsHashTheContentAndTheDefaultsNotTheLocation) {
  Folder f;
  f.Write("mine.glsl", kMine);
  f.Write("specs/copy.glsl", kMine);
  auto id_of = [&](const std::string& entry) {
    auto spec = f.Parse("[" + entry + "]");
    EXPECT_TRUE(spec.ok()) << spec.error();
    return spec ? JobId(ExpandJobs(*spec).front()) : std::string();
  };
  const std::string base = id_of(R"({"file": "../mine.glsl", "name": "mine"})");
  // The same content elsewhere, and the default spelled out: the same job.
  EXPECT_EQ(id_of(R"({"file": "copy.glsl", "name": "mine"})"), base);
  EXPECT_EQ(id_of(R"({"file": "../mine.glsl", "name": "mine", "params": {"k": 0.5}})"), base);
  EXPECT_NE(id_of(R"({"file": "../mine.glsl", "name": "mine", "params": {"k": 0.6}})"), base);
  // Another name labels other rows: another job.
  EXPECT_NE(id_of(R"({"file": "../mine.glsl", "name": "yours"})"), base);
  // An edit, even a comment, is new work.
  f.Write("mine.glsl", std::string(kMine) + "// tuned\n");
  EXPECT_NE(id_of(R"({"file": "../mine.glsl", "name": "mine"})"), base);
}

TEST(UserVariantSpec, ErrorsNameTheSpecLineAndTheFile) {
  Folder f;
  f.Write("mine.glsl", kMine);
  f.Write("broken.glsl",
          "// shimmer-param: k = 1 in [0, 2]\n"
          "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {\n"
          "  return widenedNdf(ndf, f.hpp, alpha * p.q);\n}\n");
  f.Write("baddecl.glsl", "// shimmer-param: k = 9 in [0, 2]\n");
  const std::string spec = (f.dir / "specs" / "u.json").string();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"([{"file": "nope.glsl", "name": "mine"}])", "u.json:2: file: " + (f.dir / "specs" / "nope.glsl").string() +
                                                           ": no such variant file"},
      {R"([{"file": "../broken.glsl", "name": "mine"}])", "broken.glsl:3: "},
      {R"([{"file": "../baddecl.glsl", "name": "mine"}])", "baddecl.glsl:1: k: the default 9 lies outside [0, 2]"},
      {R"([{"file": "../mine.glsl", "name": "mine", "params": {"kappa": [0.1]}}])",
       "kappa: " + (f.dir / "mine.glsl").string() + " has no parameter 'kappa' (it declares: k)"},
      {R"([{"file": "../mine.glsl", "name": "mine", "params": {"k": [5]}}])", "must be >= 0 and <= 4, got 5"},
      {R"([{"file": "../mine.glsl", "name": "tk19"}])", "'tk19' is a built-in variant's name"},
      {R"([{"file": "../mine.glsl", "name": "my variant"}])", "must be 1 to 64 letters"},
      {R"([{"file": 3, "name": "mine"}])", "file: must be the path of a variant GLSL file"},
      {R"([{"file": "../mine.glsl", "name": "mine"}, {"file": "../broken.glsl", "name": "mine"}])",
       "broken.glsl:3"},
      {R"([{"file": "../mine.glsl", "name": "mine"}, {"file": "../baddecl.glsl", "name": "x"}, "mine"])",
       "baddecl.glsl:1"},
      {R"([{"file": "../mine.glsl", "name": "mine"}, {"name": "mine", "params": {"k": [1]}}])",
       "a variant file's parameters are given where the file is"},
  };
  for (const auto& [variants, needle] : cases) {
    auto r = f.Parse(variants);
    ASSERT_FALSE(r.ok()) << variants;
    EXPECT_EQ(r.error().rfind(spec + ":", 0), 0u) << r.error();
    EXPECT_NE(r.error().find(needle), std::string::npos) << variants << "\n" << r.error();
  }
  f.Write("other.glsl", std::string(kMine) + "// other\n");
  auto twice = f.Parse(R"([{"file": "../mine.glsl", "name": "mine"}, {"file": "../other.glsl", "name": "mine"}])");
  ASSERT_FALSE(twice.ok());
  EXPECT_NE(twice.error().find("two variant files are named 'mine'"), std::string::npos) << twice.error();
}

TEST(UserVariantSpec, FitsTakeAFileVariantsDeclaredParameterWithinItsRange) {
  Folder f;
  f.Write("mine.glsl", kMine);
  auto fit_spec = [&](const std::string& fit) {
    const std::string text = R"({"name": "u", "scenes": ["sphere"], "materials": ["ggx:0.1"], "cameras": ["orbit"],
      "variants": [{"file": "../mine.glsl", "name": "mine"}], "size": [16, 16], "frames": 2,
      "fit": )" + fit + "}";
    return ParseSpec(text, (f.dir / "specs" / "u.json").string());
  };
  const std::string shots = R"("train": {"scenes": ["sphere"], "cameras": ["orbit"]},
      "validate": {"scenes": ["sphere"], "cameras": ["pan"]})";
  auto ok = fit_spec(R"({"variants": ["mine"], "param": "k", "bounds": [0.01, 4], )" + shots + "}");
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_EQ(ok->fits[0].variants, std::vector<std::string>{"mine"});
  auto wide = fit_spec(R"({"variants": ["mine"], "param": "k", "bounds": [0.01, 8], )" + shots + "}");
  ASSERT_FALSE(wide.ok());
  EXPECT_NE(wide.error().find("leave k's declared range [0, 4]"), std::string::npos) << wide.error();
  auto other = fit_spec(R"({"variants": ["mine"], "param": "fp_max", )" + shots + "}");
  ASSERT_FALSE(other.ok());
  EXPECT_NE(other.error().find("has no parameter \"fp_max\" to fit"), std::string::npos) << other.error();
  // A spec built in code takes a file the same way (shimmer fit --variant-file).
  Spec spec = *ok;
  auto added = AddUserVariant(&spec, (f.dir / "mine.glsl").string(), "mine2");
  ASSERT_TRUE(added.ok()) << added.error();
  EXPECT_TRUE(CheckFitVariant(spec, "mine2", "k", 0.1, 1).ok());
  EXPECT_FALSE(CheckFitVariant(spec, "mine2", "k", 0.1, 5).ok());
}

}  // namespace
}  // namespace shimmer::experiments
