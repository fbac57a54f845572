// The report as a sequence of blocks, built once from the rows and rendered
// twice: as markdown (report.md) and as one self-contained HTML page
// (report.html), so the two never say different things.
#pragma once

#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "decision_rule.h"
#include "report_parts.h"
#include "shimmer/experiments/fit_run.h"
#include "shimmer/experiments/sg_accuracy.h"

namespace shimmer::experiments::report {

// Text in blocks uses a small inline markup that both renderers read:
// `code`, **bold** and [text](relative-link).
struct Block {
  enum class Kind { kHeading, kParagraph, kList, kTable, kFigures };
  Kind kind = Kind::kParagraph;
  int level = 2;                    // headings
  std::string text;                 // heading or paragraph
  std::string id;                   // headings: the HTML anchor
  std::vector<std::string> items;   // list items; figures: SVG file names
  std::vector<std::string> header;  // tables
  std::vector<std::vector<std::string>> cells;
  std::vector<std::string> captions;  // figures: alt text, one per file
  bool html_only = false;             // a table of every column: report.html shows it folded, report.md leaves it out
};

struct Document {
  std::string title;
  std::vector<Block> blocks;
  void Heading(int level, const std::string& text);
  void Paragraph(const std::string& text);
  void List(std::vector<std::string> items);
  void Table(std::vector<std::string> header, std::vector<std::vector<std::string>> cells);
  void HtmlOnlyTable(std::vector<std::string> header, std::vector<std::vector<std::string>> cells);
  void Figures(std::vector<std::string> files, std::vector<std::string> captions);
};

// The text of numbers, shared by the parts of the document: a value ("n/a"
// for NaN), with its interval in brackets, a share in per cent, `code`, a
// joined list, quartiles as "median (IQR q1–q3)", and "[lo, hi]".
std::string Fmt(double v, const char* f = "%.4g");
std::string WithInterval(double v, Interval ci, const char* f = "%.4g");
std::string Percent(double share);
std::string Code(const std::string& s);
std::string Join(const std::vector<std::string>& items, const std::string& sep = ", ");
std::string Ratio(const Quartiles& q);
std::string Bounds(double lo, double hi);
// A heading's anchor as GitHub makes it ("Reference noise" -> "reference-noise").
std::string Anchor(const std::string& heading);

// The section headings every report has (the browser test looks for them).
inline constexpr const char* kAnswerHeading = "Answer";
inline constexpr const char* kContentsHeading = "Contents";
inline constexpr const char* kOverviewHeading = "Overview";
inline constexpr const char* kCellsHeading = "Cells in detail";
inline constexpr const char* kLeaderboardHeading = "Leaderboards by class";
inline constexpr const char* kHeatmapHeading = "Heatmap";
inline constexpr const char* kReferenceNoiseHeading = "Reference noise";
inline constexpr const char* kExcludedHeading = "Shots left out";
inline constexpr const char* kBeyondHeading = "Beyond the papers";
inline constexpr const char* kShotsHeading = "Shots";
inline constexpr const char* kMethodHeading = "Method";
// Only in reports whose store has external sequences.
inline constexpr const char* kExternalHeading = "External sequences";
inline constexpr const char* kSparklesHeading = "Glints: sparkles against the reference";
inline constexpr const char* kNormalMapMemoryHeading = "Normal maps: memory per texel beside error";
// Only in reports whose store has a shot lit by an SG light.
inline constexpr const char* kSgAccuracyHeading = "SG lighting: accuracy of seed 004's approximations";
// The files of that section, in the report's directory.
inline constexpr const char* kSgAccuracyStem = "sg_accuracy";

// `sg`: the SG approximation accuracy section after the overview (null: none).
// `videos`: the keys of the groups whose grid video lies beside the report.
// `engine_fits`: joint fits from a fit.json for the overview's engine-settings part.
Document BuildDocument(const std::vector<Group>& groups, const std::string& title, std::size_t jobs,
                       const SgAccuracyTable* sg = nullptr, const std::set<std::string>* videos = nullptr,
                       const std::vector<JointFit>& engine_fits = {});

// The overview's "Beyond the papers" part (report_beyond.cpp): the Jacobian
// GGX rect against seed 000's, TK19's forward filter against K16's with its
// Fig. 1 ordering, and the engine settings of `engine_fits`.
void BeyondThePapers(Document& doc, const std::vector<const Group*>& groups, const std::vector<JointFit>& engine_fits);

// The answer (report_answer.cpp): the grid of cells and how to read it, the
// cells in detail, one leaderboard per row of the grid, the rows that the
// reference's noise leaves unresolved, and the cells as CSV (cells.csv).
// `devices`: the benchmark devices (a CPU device gets a sentence saying so).
void AnswerSection(Document& doc, const std::vector<CellAnswer>& cells, const std::vector<std::string>& devices);
void CellDetails(Document& doc, const std::vector<CellAnswer>& cells);
void ClassLeaderboards(Document& doc, const std::vector<const Group*>& groups);
void ReferenceNoiseSection(Document& doc, const std::vector<const Group*>& groups);
std::string CellsCsv(const std::vector<CellAnswer>& cells);
bool CpuDevice(const std::vector<std::string>& devices);

std::string ToMarkdown(const Document& doc);
// One GitHub-flavoured table ('|' in cells escaped), ending in a newline.
std::string MarkdownTable(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows);
// `svg_of(file)` returns a figure's SVG text, or nullopt when it was not drawn.
std::string ToHtml(const Document& doc, const std::function<std::optional<std::string>(const std::string&)>& svg_of);

}  // namespace shimmer::experiments::report
