#include "shimmer/core/json_file.h"

#include <cerrno>
#include <fstream>
#include <sstream>

#include "shimmer/core/atomic_file.h"

namespace shimmer {

namespace {

// Line and column of a byte offset, 1-based, as editors count them.
std::string Position(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  int line = 1;
  std::size_t line_start = 0;
  for (std::size_t i = 0; i < offset; ++i)
    if (text[i] == '\n') ++line, line_start = i + 1;
  return std::to_string(line) + ":" + std::to_string(offset - line_start + 1);
}

// nlohmann's parse_error text is "[json.exception.parse_error.101] parse
// error at line 1, column 5: syntax error while parsing value - invalid
// literal; last read: 'tru'"; the part after the last " - " says what is wrong.
std::string Problem(const std::string& what) {
  std::string problem = what;
  if (auto dash = problem.rfind(" - "); dash != std::string::npos) problem = problem.substr(dash + 3);
  if (problem.find("number overflow") != std::string::npos) return "number out of range: " + problem;
  return problem;
}

}  // namespace

Result<nlohmann::json> ParseJson(std::string_view text, const std::string& source) {
  try {
    return nlohmann::json::parse(text.begin(), text.end());
  } catch (const nlohmann::json::parse_error& e) {
    // byte is 1-based and points after the offending token.
    const std::size_t offset = e.byte > 0 ? e.byte - 1 : 0;
    return Result<nlohmann::json>::Failure(source + ":" + Position(text, offset) + ": not valid JSON (" +
                                           Problem(e.what()) + ")");
  } catch (const nlohmann::json::out_of_range& e) {
    // "number overflow parsing '1e999'" carries no offset: find the number.
    std::string what = e.what();
    std::size_t offset = std::string_view::npos;
    if (auto open = what.find('\''), close = what.rfind('\''); open != std::string::npos && close > open)
      offset = text.find(what.substr(open + 1, close - open - 1));
    if (auto id = what.find("] "); id != std::string::npos) what = what.substr(id + 2);
    return Result<nlohmann::json>::Failure(source +
                                           (offset == std::string_view::npos ? "" : ":" + Position(text, offset)) +
                                           ": number out of range (" + what + ")");
  }
}

Result<nlohmann::json> ReadJsonFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return Result<nlohmann::json>::Failure(path.string() + ": no such file");
  if (std::filesystem::is_directory(path, ec))
    return Result<nlohmann::json>::Failure(path.string() + ": is a directory, expected a JSON file");
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return Result<nlohmann::json>::Failure(path.string() + ": cannot read (" + SystemReason(errno) + ")",
                                           ErrorCode::kIo);
  std::ostringstream text;
  text << in.rdbuf();
  return ParseJson(text.str(), path.string());
}

std::string Quote(const nlohmann::json& value, std::size_t max_chars) {
  std::string text = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (text.size() > max_chars) text = text.substr(0, max_chars) + "...";
  return text;
}

}  // namespace shimmer
