// Tables a test measures and the docs quote: the test compares its text with
// the committed file under results/tests/ and fails on any difference, or,
// with SHIMMER_UPDATE_GOLDEN=1 in the environment, rewrites the file (the
// compare/update modes of Filament's golden images, for text). The docs show
// these files through generated blocks, so no measured figure is copied by
// hand. Write only figures that do not depend on the machine's last bits
// (quadrature, not float rounding), rounded to the digits a reader needs.
#pragma once

#include <gtest/gtest.h>

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace shimmer::test {

// printf into a std::string.
inline std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));
inline std::string Format(const char* format, ...) {
  va_list args;
  va_start(args, format);
  char buffer[512];
  std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return buffer;
}

inline bool UpdatingGoldens() {
  const char* update = std::getenv("SHIMMER_UPDATE_GOLDEN");
  return update && *update && std::string(update) != "0";
}

// `name` is a file name under results/tests/ of the source tree.
inline void ExpectGoldenText(const std::string& name, const std::string& text) {
  const std::filesystem::path path = std::filesystem::path(SHIMMER_SOURCE_DIR) / "results" / "tests" / name;
  if (UpdatingGoldens()) {
    std::filesystem::create_directories(path.parent_path());
    const std::filesystem::path temporary = path.string() + ".tmp";
    { std::ofstream(temporary, std::ios::binary) << text; }
    std::filesystem::rename(temporary, path);
    return;
  }
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in) << path << " is missing: run this test with SHIMMER_UPDATE_GOLDEN=1 to write it";
  std::stringstream committed;
  committed << in.rdbuf();
  EXPECT_EQ(committed.str(), text) << path
                                   << " is not what the test measures now; if the change is meant, rerun the test "
                                      "with SHIMMER_UPDATE_GOLDEN=1, commit the file and regenerate the docs' blocks "
                                      "(scripts/readme-tour.sh --blocks-only)";
}

}  // namespace shimmer::test
