// `shimmer render` end to end: the default invocation works, bad input gets
// one clear message, a non-zero exit and no frame under a final name.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.h"

namespace {

namespace fs = std::filesystem;

using shimmer::testing::CliRun;

CliRun Shimmer(const std::string& args, const std::string& env = "XDG_RUNTIME_DIR=/tmp") {
  return shimmer::testing::RunShimmer(SHIMMER_CLI, args, env);
}

fs::path FreshDir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("shimmer_cli_test_" + name);
  fs::remove_all(d);
  return d;
}

int FrameFiles(const fs::path& dir) {
  int n = 0;
  if (!fs::exists(dir)) return 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().extension() == ".exr";
  return n;
}

void ExpectOneClearError(const CliRun& r, const std::string& needle) {
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("shimmer: error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(needle), std::string::npos) << r.output;
}

TEST(GpuCli, DefaultsRenderASequenceAndItsReference) {
  fs::path dir = FreshDir("defaults"), ref = FreshDir("defaults_ref");
  CliRun r = Shimmer("render --scene sphere-field --camera orbit --variant none --frames 3 --size 32 32 --out " +
                     dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(FrameFiles(dir), 3);
  CliRun rr = Shimmer(
      "render --scene sphere-field --camera orbit --variant none --frames 2 --size 32 32 "
      "--reference-spp 2 --out " +
      ref.string());
  ASSERT_EQ(rr.exit_code, 0) << rr.output;
  EXPECT_EQ(FrameFiles(ref), 2);
  std::ifstream in(ref / "sequence.json");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"reference\": true"), std::string::npos);
  EXPECT_NE(text.find("\"spp\": 4"), std::string::npos);
  fs::remove_all(dir);
  fs::remove_all(ref);
}

TEST(GpuCli, UserVariantFileRendersAndCompileErrorsNameFileAndLine) {
  fs::path dir = FreshDir("user"), file = fs::temp_directory_path() / "shimmer_cli_user_variant.glsl";
  {
    std::ofstream f(file);
    f << "// doubles the roughness\n"
         "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {\n"
         "  return evalVariant(VARIANT_NONE, ndf, alpha * real(2), f, variantParams(p));\n"
         "}\n";
  }
  CliRun ok = Shimmer("render --scene sphere --frames 1 --size 16 16 --variant-file " + file.string() + " --out " +
                      dir.string());
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_EQ(FrameFiles(dir), 1);
  fs::remove_all(dir);
  {
    std::ofstream f(file);
    f << "FilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, UserParams p) {\n"
         "  return undefinedThing(alpha);\n"
         "}\n";
  }
  CliRun bad = Shimmer("render --scene sphere --frames 1 --size 16 16 --variant-file " + file.string() + " --out " +
                       dir.string());
  ExpectOneClearError(bad, file.string() + ":2");
  EXPECT_EQ(FrameFiles(dir), 0);
  fs::remove(file);
  fs::remove_all(dir);
}

nlohmann::json NdfJson(const std::string& args) {
  CliRun r = Shimmer("ndf --json " + args);
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
  if (r.exit_code != 0) return nlohmann::json::object();
  return nlohmann::json::parse(r.output);
}

// `shimmer ndf --variant-file` runs the user's GLSL on the device: the
// documented tk19 file gives the built-in tk19's numbers, on the device and
// against the CPU oracle in float, and the 5-tap density filter with
// fp_max = 0 gives `none`.
TEST(GpuCli, NdfOfAUserVariantEqualsTheSameFormulaBuiltIn) {
  const std::string examples = std::string(SHIMMER_SOURCE_DIR) + "/examples/variants/";
  const std::vector<std::string> points = {
      "--alpha 0.05 --slope 0.1 0.2 --footprint 0.1 0.05", "--alpha 0.3 0.1 --slope -1.5 0.4 --footprint 0 0",
      "--alpha 0.01 --slope 3 -2 --footprint 2 0.5 --param sigma2=0.5 --param kappa=0.9",
      "--ndf beckmann --alpha 0.2 --slope 0.01 0 --footprint 0.02 0.3 --param sigma2=0.1"};
  for (const std::string& at : points) {
    const nlohmann::json user = NdfJson("--variant-file " + examples + "tk19_as_user_variant.glsl " + at);
    const nlohmann::json device = NdfJson("--variant tk19 --on-device " + at);
    const nlohmann::json cpu = NdfJson("--variant tk19 --precision float " + at);
    ASSERT_TRUE(user.contains("density")) << at;
    EXPECT_EQ(user["precision"], "float");
    EXPECT_EQ(user["params"], cpu["params"]) << at;
    for (const char* key : {"slope_density", "density"}) {
      const double u = user[key], d = device[key], c = cpu[key];
      EXPECT_GT(u, 0) << at;
      EXPECT_NEAR(u, d, 1e-5 * std::fabs(d)) << key << " " << at;
      EXPECT_NEAR(u, c, 1e-5 * std::fabs(c)) << key << " " << at;
    }
    EXPECT_NEAR(double(user["alpha_eff"][0]), double(cpu["alpha_eff"][0]), 1e-6) << at;
  }
  const std::string at = "--alpha 0.1 --slope 0 0 --footprint 0.2 0.2";  // at the peak
  const nlohmann::json box0 = NdfJson("--variant-file " + examples + "footprint_box_density.glsl --param fp_max=0 " + at);
  const nlohmann::json none = NdfJson("--variant none --precision float " + at);
  EXPECT_NEAR(double(box0["density"]), double(none["density"]), 1e-5 * double(none["density"]));
  const nlohmann::json box = NdfJson("--variant-file " + examples + "footprint_box_density.glsl " + at);
  EXPECT_LT(double(box["density"]), 0.99 * double(none["density"])) << "a footprint filters the peak down";
}

TEST(GpuCli, VariantsFileListsDeclaredParametersAndChecksTheFile) {
  const std::string file = std::string(SHIMMER_SOURCE_DIR) + "/examples/variants/tk19_as_user_variant.glsl";
  CliRun r = Shimmer("variants --json --file " + file);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j.size(), 1u);
  ASSERT_EQ(j[0]["params"].size(), 2u);
  EXPECT_EQ(j[0]["params"][0]["name"], "sigma2");
  EXPECT_EQ(j[0]["params"][0]["default"], 0.25);
  EXPECT_EQ(j[0]["params"][1]["name"], "kappa");
  EXPECT_EQ(j[0]["params"][1]["range"], nlohmann::json::array({0, 10000}));
  const fs::path bad = fs::temp_directory_path() / "shimmer_cli_bad_variant.glsl";
  {
    std::ofstream f(bad);
    f << "// shimmer-param: k = 1 in [0, 2]\nFilteredNdf userVariant(int ndf, vec2 alpha, ShadingFootprint f, "
         "UserParams p) {\n  return widenedNdf(ndf, f.hpp, alpha * p.q);\n}\n";
  }
  ExpectOneClearError(Shimmer("variants --file " + bad.string()), bad.string() + ":3");
  fs::remove(bad);
}

TEST(GpuCli, NdfOfAUserVariantRefusesWhatItCannotDo) {
  const std::string file = std::string(SHIMMER_SOURCE_DIR) + "/examples/variants/tk19_as_user_variant.glsl";
  ExpectOneClearError(Shimmer("ndf --variant-file " + file + " --precision double"), "--precision double");
  ExpectOneClearError(Shimmer("ndf --variant-file " + file + " --param fp_max=1"), "has no parameter 'fp_max'");
  ExpectOneClearError(Shimmer("ndf --variant-file " + file + " --param sigma2=-1"), "parameter sigma2");
  ExpectOneClearError(Shimmer("ndf --variant-file nope.glsl"), "nope.glsl: no such variant file");
  ExpectOneClearError(Shimmer("ndf --variant tk19 --variant-file " + file), "both name the filter; give one");
}

TEST(GpuCli, BadInputGetsOneMessageAndNoFrames) {
  fs::path dir = FreshDir("bad");
  const std::string base = "render --frames 2 --size 16 16 --out " + dir.string() + " ";
  ExpectOneClearError(Shimmer(base + "--scene no-such-scene"), "unknown scene 'no-such-scene'");
  ExpectOneClearError(Shimmer(base + "--variant no-such-variant"), "unknown variant 'no-such-variant'");
  ExpectOneClearError(Shimmer(base + "--variant tk19 --param fp_max=1"), "has no parameter 'fp_max'");
  ExpectOneClearError(Shimmer(base + "--variant tk19 --param sigma2=abc"), "is not a finite number");
  ExpectOneClearError(Shimmer(base + "--material phong:0.1"), "NDF must be ggx, beckmann, blinn-phong or glints");
  ExpectOneClearError(Shimmer(base + "--material blinn-phong:-3"),
                      "Blinn-Phong power '-3' must be a number in [0, 1e8]");
  ExpectOneClearError(Shimmer(base + "--variant toksvig"), "filters normal maps, and scene");
  ExpectOneClearError(Shimmer(base + "--variant tk19+tk21"), "unknown variant 'tk19+tk21'");
  ExpectOneClearError(Shimmer(base + "--camera spin"),
                      "--camera must be one of orbit, pan, dolly, vr-jitter, static, got 'spin'");
  ExpectOneClearError(Shimmer(base + "--derivatives sobel"), "--derivatives");
  ExpectOneClearError(Shimmer(base + "--variant k16-ggx-rect --material beckmann:0.1"), "GGX only");
  ExpectOneClearError(Shimmer(base + "--variant tk19 --reference-spp 4"), "reference renders variant none");
  EXPECT_EQ(FrameFiles(dir), 0);
  fs::remove_all(dir);
}

TEST(GpuCli, UnwritableOutputDirectory) {
  fs::path file = fs::temp_directory_path() / "shimmer_cli_not_a_dir";
  { std::ofstream(file) << "x"; }
  CliRun r = Shimmer("render --scene sphere --frames 1 --size 16 16 --out " + (file / "sub").string());
  ExpectOneClearError(r, "cannot create the output directory");
  fs::remove(file);
}

TEST(GpuCli, NoVulkanDevice) {
  fs::path dir = FreshDir("nodevice");
  CliRun r =
      Shimmer("render --scene sphere --frames 1 --size 16 16 --out " + dir.string(),
              "XDG_RUNTIME_DIR=/tmp VK_ICD_FILENAMES=/nonexistent/icd.json VK_DRIVER_FILES=/nonexistent/icd.json");
  ExpectOneClearError(r, "Vulkan");
  EXPECT_EQ(FrameFiles(dir), 0);
  CliRun named = Shimmer("render --scene sphere --frames 1 --size 16 16 --device no-such-gpu --out " + dir.string());
  ExpectOneClearError(named, "no Vulkan device matches 'no-such-gpu'");
  fs::remove_all(dir);
}

}  // namespace
