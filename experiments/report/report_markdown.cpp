// report.md: the document as GitHub-flavoured markdown.
#include <sstream>

#include "report_document.h"

namespace shimmer::experiments::report {

namespace {

std::string Cell(const std::string& text) {
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

}  // namespace

std::string MarkdownTable(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
  std::ostringstream md;
  md << "|";
  for (const std::string& h : header) md << " " << Cell(h) << " |";
  md << "\n|";
  for (std::size_t i = 0; i < header.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& row : rows) {
    md << "|";
    for (const std::string& c : row) md << " " << Cell(c) << " |";
    md << "\n";
  }
  return md.str();
}

std::string ToMarkdown(const Document& doc) {
  std::ostringstream md;
  md << "# " << doc.title << "\n\n";
  for (const Block& b : doc.blocks) {
    switch (b.kind) {
      case Block::Kind::kHeading: md << std::string(b.level, '#') << " " << b.text << "\n\n"; break;
      case Block::Kind::kParagraph: md << b.text << "\n\n"; break;
      case Block::Kind::kList:
        for (const std::string& item : b.items) md << "- " << item << "\n";
        md << "\n";
        break;
      case Block::Kind::kTable:
        if (!b.html_only) md << MarkdownTable(b.header, b.cells) << "\n";
        break;
      case Block::Kind::kFigures:
        for (std::size_t i = 0; i < b.items.size(); ++i)
          md << (i ? " " : "") << "![" << (i < b.captions.size() ? b.captions[i] : "") << "](" << b.items[i] << ")";
        md << "\n\n";
        break;
    }
  }
  return md.str();
}

}  // namespace shimmer::experiments::report
