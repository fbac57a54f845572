// report.html: the document as one self-contained page: the plots' SVG
// inlined, the style in the head, no script and no external reference, so
// that it opens from the file system and can be mailed as one file.
#include <sstream>

#include "report_document.h"

namespace shimmer::experiments::report {

namespace {

constexpr const char* kStyle =
    R"(body{font:14px/1.45 system-ui,sans-serif;margin:1.5em auto;max-width:1400px;padding:0 1em;color:#222}
h1,h2{border-bottom:1px solid #ccc}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:12px}
th,td{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}
th{background:#f2f2f2;position:sticky;top:0}
tr:nth-child(even) td{background:#fafafa}
code{font-size:12px;background:#f4f4f4;padding:0 2px}
.figures{display:flex;flex-wrap:wrap;gap:8px}
figure{margin:0;flex:1 1 420px;max-width:900px}
figure:only-child{max-width:100%}
figure svg{width:100%;height:auto}
figcaption{font-size:12px;color:#555}
.missing{color:#a00})";

std::string Escape(std::string_view text) {
  std::string out;
  for (char c : text) switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  return out;
}

// The document's inline markup: `code`, **bold**, [text](link).
std::string Inline(const std::string& text) {
  std::string out;
  bool bold = false;
  for (std::size_t i = 0; i < text.size();) {
    if (text[i] == '`') {
      const std::size_t end = text.find('`', i + 1);
      if (end != std::string::npos) {
        out += "<code>" + Escape(text.substr(i + 1, end - i - 1)) + "</code>";
        i = end + 1;
        continue;
      }
    }
    if (text.compare(i, 2, "**") == 0) {
      out += bold ? "</strong>" : "<strong>";
      bold = !bold;
      i += 2;
      continue;
    }
    if (text[i] == '[') {
      const std::size_t close = text.find("](", i);
      const std::size_t end = close == std::string::npos ? close : text.find(')', close);
      if (end != std::string::npos) {
        out += "<a href=\"" + Escape(text.substr(close + 2, end - close - 2)) + "\">" +
               Escape(text.substr(i + 1, close - i - 1)) + "</a>";
        i = end + 1;
        continue;
      }
    }
    out += Escape(text.substr(i, 1));
    ++i;
  }
  if (bold) out += "</strong>";
  return out;
}

// gnuplot's SVG from its <svg> element on: the XML prolog is not HTML.
std::string InlineSvg(const std::string& svg) {
  const std::size_t start = svg.find("<svg");
  return start == std::string::npos ? std::string() : svg.substr(start);
}

}  // namespace

std::string ToHtml(const Document& doc, const std::function<std::optional<std::string>(const std::string&)>& svg_of) {
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" << Escape(doc.title)
       << "</title>\n<style>\n"
       << kStyle << "\n</style>\n</head>\n<body>\n<h1>" << Escape(doc.title) << "</h1>\n";
  for (const Block& b : doc.blocks) {
    switch (b.kind) {
      case Block::Kind::kHeading:
        html << "<h" << b.level << " id=\"" << Escape(b.id) << "\">" << Inline(b.text) << "</h" << b.level << ">\n";
        break;
      case Block::Kind::kParagraph: html << "<p>" << Inline(b.text) << "</p>\n"; break;
      case Block::Kind::kList:
        html << "<ul>\n";
        for (const std::string& item : b.items) html << "<li>" << Inline(item) << "</li>\n";
        html << "</ul>\n";
        break;
      case Block::Kind::kTable:
        if (b.html_only) html << "<details><summary>every column</summary>\n";
        html << "<table>\n<thead><tr>";
        for (const std::string& h : b.header) html << "<th>" << Inline(h) << "</th>";
        html << "</tr></thead>\n<tbody>\n";
        for (const auto& row : b.cells) {
          html << "<tr>";
          for (const std::string& c : row) html << "<td>" << Inline(c) << "</td>";
          html << "</tr>\n";
        }
        html << "</tbody>\n</table>\n";
        if (b.html_only) html << "</details>\n";
        break;
      case Block::Kind::kFigures:
        html << "<div class=\"figures\">\n";
        for (std::size_t i = 0; i < b.items.size(); ++i) {
          const std::string caption = i < b.captions.size() ? b.captions[i] : b.items[i];
          const std::optional<std::string> svg = svg_of(b.items[i]);
          const std::string body = svg ? InlineSvg(*svg) : std::string();
          html << "<figure>\n";
          if (body.empty())
            html << "<p class=\"missing\">" << Escape(b.items[i])
                 << " was not drawn (no gnuplot, or nothing to plot)</p>\n";
          else
            html << body << "\n";
          html << "<figcaption>" << Escape(caption) << "</figcaption>\n</figure>\n";
        }
        html << "</div>\n";
        break;
    }
  }
  html << "</body>\n</html>\n";
  return html.str();
}

}  // namespace shimmer::experiments::report
