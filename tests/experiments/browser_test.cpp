// report.html opened as a user would: headless Chromium loads it from the
// file system, and the page must render every section without console or
// loading errors. Skipped where Chromium (the Debian package `chromium`) is
// not installed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "report_document.h"
#include "shimmer/experiments/report.h"

namespace shimmer::experiments {
namespace {

namespace fs = std::filesystem;

std::string ReadText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

bool HasChromium() { return std::system("command -v chromium >/dev/null 2>&1") == 0; }

// A report of two shots, one unconverged, with intervals and benchmarks.
std::vector<JobResult> Rows() {
  std::vector<JobResult> rows;
  for (const char* material : {"ggx:0.01", "ggx:0.3"})
    for (auto [variant, err, bias] : {std::tuple<const char*, double, double>{"none", 1.0, 0.0},
                                      {"tk21", 0.3, 0.02},
                                      {"vlachos15", 0.1, -0.4},
                                      {"supersample-2", 0.5, 0.0}}) {
      JobResult r;
      r.job.scene = "sphere";
      r.job.material = material;
      r.job.camera = "orbit";
      r.job.variant = variant;
      r.job.derivatives = "quad";
      r.metrics = {{"tv_err", err},
                   {"energy_bias", bias},
                   {"relmse", 0.1},
                   {"ci95", {{"tv_err", {0.9 * err, 1.1 * err}}}},
                   {"flicker", {{"flicker_index", err}, {"freq_hz", {0.0, 7.5, 15.0}}, {"psd", {1e-3, 2e-3, 1e-4}}}}};
      r.gpu_ms_per_frame = 1 + err;
      r.device = "test gpu";
      ShotCheck check;
      check.converged = std::string(material) == "ggx:0.01";
      r.shot = check;
      BenchmarkCost cost;
      cost.device = "test gpu", cost.median_ms = 2 + err, cost.ratio_to_none = (2 + err) / 3;
      r.cost = cost;
      rows.push_back(r);
    }
  return rows;
}

TEST(Browser, ReportHtmlRendersEverySectionWithoutErrors) {
  if (!HasChromium()) GTEST_SKIP() << "chromium is not installed (Debian package `chromium`): report.html not opened";
  const fs::path dir = fs::temp_directory_path() / ("shimmer-browser-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<std::string> warnings;
  ASSERT_TRUE(WriteReport(Rows(), "Browser check", (dir / "rep").string(), &warnings));
  const std::string url = "file://" + (dir / "rep" / "report.html").string();
  const std::string chromium = "timeout 180 chromium --headless --disable-gpu --no-sandbox --user-data-dir='" +
                               (dir / "profile").string() + "' --enable-logging=stderr --v=0 ";
  const std::string dom_cmd = chromium + "--dump-dom '" + url + "' >'" + (dir / "dom.html").string() + "' 2>'" +
                              (dir / "log.txt").string() + "'";
  ASSERT_EQ(std::system(dom_cmd.c_str()), 0) << dom_cmd << "\n" << ReadText(dir / "log.txt");
  const std::string dom = ReadText(dir / "dom.html");
  for (const char* section :
       {report::kAnswerHeading, report::kOverviewHeading, report::kCellsHeading, report::kLeaderboardHeading, report::kHeatmapHeading,
        report::kExcludedHeading, report::kShotsHeading, report::kMethodHeading})
    EXPECT_NE(dom.find(">" + std::string(section) + "</h"), std::string::npos) << section;
  EXPECT_NE(dom.find("sphere / ggx:0.3 / orbit"), std::string::npos);  // the unconverged shot, listed
  EXPECT_NE(dom.find("<table"), std::string::npos);
  if (fs::exists(dir / "rep" / "heatmap.svg")) {
    EXPECT_NE(dom.find("<svg"), std::string::npos);
  }
  // The page's own messages: console output, resources that failed to load.
  const std::string log = ReadText(dir / "log.txt");
  for (const char* error : {"CONSOLE", "Uncaught", "Failed to load resource", "net::ERR_"})
    EXPECT_EQ(log.find(error), std::string::npos) << error << " in\n" << log;

  const std::string shot_cmd = chromium + "--window-size=1400,2000 --screenshot='" + (dir / "page.png").string() +
                               "' '" + url + "' >/dev/null 2>&1";
  ASSERT_EQ(std::system(shot_cmd.c_str()), 0) << shot_cmd;
  ASSERT_TRUE(fs::exists(dir / "page.png"));
  // A blank 1400x2000 page compresses to a few kilobytes; tables, text and plots do not.
  EXPECT_GT(fs::file_size(dir / "page.png"), 30000u);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace shimmer::experiments
