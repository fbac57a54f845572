// The metrics code's version (cmake/HashFilesScript.cmake, what a stored
// row's id carries): a comment or white-space edit leaves it, a code edit
// moves it, and no hashed file has a string literal the comment stripper
// would cut.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "test_sequences.h"

namespace shimmer::metrics {
namespace {

namespace fs = std::filesystem;

std::string Read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The version the build's script gives one file named `name` with `text`.
std::string VersionOf(const fs::path& scratch, const std::string& text, const std::string& name) {
  static int call = 0;
  const fs::path dir = scratch / std::to_string(call++);
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  const fs::path out = dir / "version.cpp";
  const std::string command = std::string(SHIMMER_CMAKE) + " -DOUT=" + out.string() +
                              " -DNAMESPACE=n -DFUNCTION=F -DFILES=" + (dir / name).string() + " -P " +
                              SHIMMER_SOURCE_DIR + "/cmake/HashFilesScript.cmake";
  if (std::system(command.c_str()) != 0) return "(script failed)";
  std::smatch digest;
  const std::string generated = Read(out);
  return std::regex_search(generated, digest, std::regex("\"([0-9a-f]{16})\"")) ? digest[1].str() : "(none)";
}

TEST(MetricsVersion, IgnoresCommentsAndWhiteSpaceButNotCode) {
  testing::TempDir scratch;
  const std::string name = "block_bootstrap.cpp";
  const std::string code = Read(fs::path(SHIMMER_SOURCE_DIR) / "metrics/src" / name);
  ASSERT_NE(code.find("// "), std::string::npos);
  const std::string version = VersionOf(scratch.path(), code, name);
  ASSERT_EQ(version.size(), 16u);

  // Every line comment reworded, a block comment added, lines re-indented.
  std::string commented = std::regex_replace(code, std::regex("// "), "// reworded: ");
  commented = "/* a new\n * block comment */\n" + std::regex_replace(commented, std::regex("\n  "), "\n    ");
  ASSERT_NE(commented, code);
  EXPECT_EQ(VersionOf(scratch.path(), commented, name), version);

  // One constant of the code changed.
  std::string edited = code;
  const size_t at = edited.find("0.975");
  ASSERT_NE(at, std::string::npos);
  edited.replace(at, 5, "0.970");
  EXPECT_NE(VersionOf(scratch.path(), edited, name), version);
  // The file's name is part of it: the same code moved to another file is other code.
  EXPECT_NE(VersionOf(scratch.path(), code, "other.cpp"), version);
}

TEST(MetricsVersion, NoHashedFileHasACommentMarkerInAStringLiteral) {
  const fs::path root(SHIMMER_SOURCE_DIR);
  std::vector<fs::path> files = {root / "core/src/exr_input.cpp", root / "core/include/shimmer/core/exr_input.h"};
  for (const fs::path& dir : {root / "metrics/src", root / "metrics/include/shimmer/metrics"})
    for (const auto& entry : fs::directory_iterator(dir)) files.push_back(entry.path());
  const std::regex literal("\"([^\"\\\\\\n]|\\\\.)*(//|/\\*)([^\"\\\\\\n]|\\\\.)*\"");
  for (const fs::path& file : files) {
    std::istringstream lines(Read(file));
    std::string line;
    int number = 0;
    while (std::getline(lines, line)) {
      ++number;
      // Only code before a line comment can hold a literal.
      const std::string code = line.substr(0, line.find("// "));
      EXPECT_FALSE(std::regex_search(code, literal)) << file << ":" << number << ": " << line;
    }
  }
}

}  // namespace
}  // namespace shimmer::metrics
