#include "shimmer/core/json_file.h"

#include <gtest/gtest.h>

#include <fstream>

#include "temp_dir.h"

namespace shimmer {
namespace {

TEST(JsonFile, SyntaxErrorsGiveLineAndColumnWithoutLibraryWording) {
  auto r = ParseJson("{\n  \"a\": 1,\n  \"b\": tru\n}", "s.json");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().rfind("s.json:3:", 0), 0u) << r.error();
  EXPECT_EQ(r.error().find("json.exception"), std::string::npos) << r.error();
}

TEST(JsonFile, NumberOverflowNamesItsPlace) {
  auto r = ParseJson("{\"a\": [1,\n 1e999]}", "n.json");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().rfind("n.json:2:2: number out of range", 0), 0u) << r.error();
  EXPECT_EQ(r.error().find("json.exception"), std::string::npos) << r.error();
}

TEST(JsonFile, MissingFileAndDirectoryAreNamed) {
  testing::TempDir dir;
  EXPECT_EQ(ReadJsonFile(dir / "none.json").error(), (dir / "none.json").string() + ": no such file");
  EXPECT_NE(ReadJsonFile(dir.path()).error().find("is a directory"), std::string::npos);
  std::ofstream(dir / "ok.json") << R"({"x": [1, 2]})";
  auto ok = ReadJsonFile(dir / "ok.json");
  ASSERT_TRUE(ok) << ok.error();
  EXPECT_EQ((*ok)["x"][1], 2);
  EXPECT_EQ(Quote(nlohmann::json(std::string(100, 'a')), 10), "\"aaaaaaaaa...");
}

}  // namespace
}  // namespace shimmer
