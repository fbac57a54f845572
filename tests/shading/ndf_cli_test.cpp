// `shimmer ndf` end to end: inputs that do not fit the evaluation precision
// are refused with one error line naming the option and the value (exit 2),
// and hard inputs that do fit come out finite for every variant.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

#include "cli_run.h"
#include "shimmer/shading/shading.h"

namespace {

using shimmer::testing::CliRun;

CliRun Shimmer(const std::string& args) { return shimmer::testing::RunShimmer(SHIMMER_CLI, args); }

// Exit 2 and exactly one line, the error, which holds `needle`.
void ExpectRefused(const std::string& args, const std::string& needle) {
  const CliRun r = Shimmer(args);
  EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
  EXPECT_EQ(r.output.rfind("shimmer: error: ", 0), 0u) << args << "\n" << r.output;
  EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << args << "\n" << r.output;
  EXPECT_NE(r.output.find(needle), std::string::npos) << args << "\n" << r.output;
}

TEST(NdfCli, RefusesValuesThatOverflowTheEvaluationPrecision) {
  ExpectRefused("ndf --precision float --alpha 1e39", "--alpha 1e+39 is out of range for --precision float");
  ExpectRefused("ndf --precision float --alpha 0.1 1e39", "--alpha 1e+39");
  ExpectRefused("ndf --precision float --slope 0 -1e39", "--slope -1e+39 is out of range for --precision float");
  ExpectRefused("ndf --precision float --footprint 1e300 0", "--footprint 1e+300 is out of range");
  // The derivatives are 2 FX: a half-side that fits float can still overflow them.
  ExpectRefused("ndf --precision float --variant tk19 --footprint 0 3e38", "--footprint 3e+38");
  ExpectRefused("ndf --precision double --variant toksvig-quad --footprint 1e308 0", "--footprint 1e+308");
  // Bad parameter values get the shading table's message.
  ExpectRefused("ndf --variant tk19 --param sigma2=-1", "parameter sigma2 must be >= 0 and <= 10000, got -1");
  ExpectRefused("ndf --variant k16-ggx-rect --param fp_min_cap=1e39 --precision float",
                "parameter fp_min_cap must be >= 0 and <= 100, got 1e+39");
  ExpectRefused("ndf --alpha -0.5", "--alpha must be > 0, got -0.5");
}

TEST(NdfCli, GlintVariantsAreRendered) {
  ExpectRefused("ndf --variant glints-zk16", "reads a glint material's texture-space process");
}

TEST(NdfCli, HardInputsThatFitComeOutFiniteForEveryVariant) {
  // Float only: each run starts the whole binary (about 0.2 s).
  for (const auto& v : shimmer::shading::Variants()) {
    if (v.glints) continue;  // refused: GlintVariantsAreRendered
    const std::string args = "ndf --json --precision float --variant " + std::string(v.name) +
                             " --alpha 1e-40 3e38 --slope 1e30 -1e30 --footprint 1e38 0";
    const CliRun r = Shimmer(args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    // nlohmann writes NaN and Inf as null.
    EXPECT_EQ(r.output.find("null"), std::string::npos) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("\"density\""), std::string::npos) << args << "\n" << r.output;
  }
}

}  // namespace
