// The README as the front door: short, its two set-up commands first, every
// generated block equal to the file it comes from (scripts/readme-tour.sh
// writes them), the tolerances it quotes equal to the decision rule's, and
// no other measured figure in its prose.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>

#include "decision_rule.h"
#include "report_document.h"
#include "shimmer/experiments/output_files.h"

namespace shimmer::experiments {
namespace {

namespace fs = std::filesystem;

const fs::path kRoot = SHIMMER_SOURCE_DIR;

std::string Read(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  EXPECT_TRUE(in) << file;
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// The first table at or after line `start` of `text`.
std::string FirstTable(const std::string& text, std::size_t start) {
  std::size_t table = text.find("\n|", start) + 1;
  std::string out;
  while (table < text.size() && text[table] == '|') {
    const std::size_t end = text.find('\n', table);
    out += text.substr(table, end - table + 1);
    table = end + 1;
  }
  return out;
}

// What readme-tour.sh puts in a block: a console transcript, a report's
// answer grid (its first table after "## Answer"), or the first table after
// the heading with a given anchor (REPORT#table:ANCHOR).
std::string Expected(const std::string& source) {
  const std::size_t hash = source.find('#');
  const std::string text = Read(kRoot / source.substr(0, hash));
  if (hash == std::string::npos) return "```console\n" + text + "```\n";
  const std::string part = source.substr(hash + 1);
  if (part == "answer") {
    const std::size_t answer = text.find("\n## Answer\n");
    EXPECT_NE(answer, std::string::npos) << source;
    return FirstTable(text, answer);
  }
  EXPECT_EQ(part.rfind("table:", 0), 0u) << source;
  const std::string want = part.substr(6);
  std::size_t line = 0;
  while (line < text.size()) {
    const std::size_t end = text.find('\n', line);
    const std::string l = text.substr(line, end - line);
    if (!l.empty() && l[0] == '#') {
      const std::size_t title = l.find_first_not_of("# ");
      if (title != std::string::npos && report::Anchor(l.substr(title)) == want) return FirstTable(text, end);
    }
    if (end == std::string::npos) break;
    line = end + 1;
  }
  ADD_FAILURE() << source << ": no heading with that anchor";
  return "";
}

// Every generated block of `page` against its source; how many there were.
int CheckGeneratedBlocks(const fs::path& page) {
  const std::string text = Read(page);
  const std::regex block("<!-- generated from (\\S+) -->\n([\\s\\S]*?)<!-- end generated -->");
  int blocks = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), block); it != std::sregex_iterator(); ++it) {
    const std::string source = (*it)[1];
    EXPECT_EQ((*it)[2].str(), Expected(source)) << page << ": " << source << ": run scripts/readme-tour.sh --blocks-only";
    ++blocks;
  }
  return blocks;
}

TEST(Readme, IsShortAndOpensWithTheTwoSetUpCommands) {
  const std::string readme = Read(kRoot / "README.md");
  EXPECT_LE(std::count(readme.begin(), readme.end(), '\n'), 250);
  const std::size_t fence = readme.find("```sh\n");
  ASSERT_NE(fence, std::string::npos);
  const std::string block = readme.substr(fence, readme.find("```\n", fence + 6) - fence);
  EXPECT_NE(block.find("bash scripts/quickstart.sh"), std::string::npos) << block;
  EXPECT_NE(block.find("bash scripts/test.sh"), std::string::npos) << block;
  EXPECT_LT(fence, readme.find("\n## "));  // before any section
  EXPECT_NE(Read(kRoot / ".ci" / "run").find("scripts/test.sh"), std::string::npos);
}

TEST(Readme, GeneratedBlocksEqualTheirSources) {
  EXPECT_GE(CheckGeneratedBlocks(kRoot / "README.md"), 6);
  EXPECT_NE(Read(kRoot / "README.md").find("<!-- generated from results/standard/report.md#answer -->"),
            std::string::npos);
}

TEST(Docs, GeneratedBlocksEqualTheirSources) {
  int blocks = 0;
  for (const auto& entry : fs::directory_iterator(kRoot / "docs"))
    if (entry.path().extension() == ".md") blocks += CheckGeneratedBlocks(entry.path());
  EXPECT_GE(blocks, 2);
}

// Outside generated blocks, code and links, the only figures are the rule's
// tolerances (equal to its constants) and fixed facts (versions, the
// interval's level, the reference pattern of the tour's command).
TEST(Readme, ProseQuotesNoFigureButTheRulesTolerances) {
  std::string prose = Read(kRoot / "README.md");
  for (const char* pattern : {"<!-- generated from [\\s\\S]*?<!-- end generated -->", "```[\\s\\S]*?```", "`[^`\\n]*`",
                              "\\]\\([^)]*\\)"})
    prose = std::regex_replace(prose, std::regex(pattern), " ");
  EXPECT_NE(prose.find(FormatNumber(report::kSpatialTolerance, "%g") + "×"), std::string::npos);
  const std::regex figure("\\d+(\\.\\d+)?\\s?(%|×|x\\b|ms\\b|min\\b|minutes|seconds|s\\b)");
  const std::set<std::string> allowed = {"95 %", "10 %", FormatNumber(report::kSpatialTolerance, "%g") + "×", "4×"};
  for (auto it = std::sregex_iterator(prose.begin(), prose.end(), figure); it != std::sregex_iterator(); ++it)
    EXPECT_TRUE(allowed.count(it->str())) << "a hand-copied figure in the README: " << it->str();
  EXPECT_NE(prose.find("±" + FormatNumber(100 * report::kEnergyTolerance, "%g") + " %"), std::string::npos);
}

}  // namespace
}  // namespace shimmer::experiments
