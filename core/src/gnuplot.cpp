#include "shimmer/core/gnuplot.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <vector>

#include "shimmer/core/atomic_file.h"

namespace shimmer {

namespace fs = std::filesystem;

namespace {

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The files a script draws: its "set output '<name>'" lines.
std::vector<std::string> Outputs(const fs::path& script) {
  std::vector<std::string> names;
  std::ifstream in(script);
  for (std::string line; std::getline(in, line);) {
    const std::string prefix = "set output '";
    if (line.rfind(prefix, 0) != 0) continue;
    std::string name;
    for (std::size_t i = prefix.size(); i < line.size(); ++i) {
      if (line[i] == '\'' && i + 1 < line.size() && line[i + 1] == '\'') {
        name += '\'', ++i;  // GnuplotString's quote
      } else if (line[i] == '\'') {
        break;
      } else {
        name += line[i];
      }
    }
    if (!name.empty()) names.push_back(name);
  }
  return names;
}

// Whether a drawn SVG or PNG ends as its format ends (other formats are not checked).
bool Whole(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff tail_size = std::min<std::streamoff>(size, 64);
  std::string tail(std::size_t(std::max<std::streamoff>(tail_size, 0)), '\0');
  in.seekg(size - tail_size);
  in.read(tail.data(), tail_size);
  const std::string ext = file.extension().string();
  if (ext == ".svg") return tail.find("</svg>") != std::string::npos;
  if (ext == ".png") return tail.size() >= 8 && tail.compare(tail.size() - 8, 8, "IEND\xAE\x42\x60\x82") == 0;
  return true;
}

}  // namespace

bool GnuplotAvailable() {
  static const bool available = std::system("command -v gnuplot >/dev/null 2>&1") == 0;
  return available;
}

Status RunGnuplot(const fs::path& dir, const std::string& script) {
  if (!GnuplotAvailable())
    return Status::Failure("gnuplot is not installed: wrote " + (dir / script).string() + " but not its plot",
                           ErrorCode::kInternal);
  const std::string where = dir.empty() ? std::string(".") : dir.string();
  const std::string command = "cd " + ShellQuote(where) + " && gnuplot " + ShellQuote(script) + " >/dev/null 2>&1";
  if (std::system(command.c_str()) != 0)
    return Status::Failure("gnuplot failed on " + (dir / script).string(), ErrorCode::kInternal);
  // gnuplot ignores write errors: on a full disk it exits 0 and leaves a plot
  // cut short, which must not pass for a drawn one.
  std::error_code ec;
  for (const std::string& name : Outputs(dir / script))
    if (fs::exists(dir / name, ec) && !Whole(dir / name))
      return Status::Failure((dir / name).string() + ": cannot write the plot (gnuplot stopped after " +
                                 std::to_string(fs::file_size(dir / name, ec)) +
                                 " bytes: the disk is full or a file-size limit was reached)",
                             ErrorCode::kIo);
  return Ok();
}

Result<std::optional<std::string>> WritePlot(const fs::path& dir, const std::string& script_name,
                                             const std::string& output, const std::string& script_text) {
  using R = Result<std::optional<std::string>>;
  if (Status s = WriteFileAtomic(dir / script_name, script_text); !s) return s.failure();
  Status drawn = RunGnuplot(dir, script_name);
  std::error_code ec;
  if (drawn && !fs::exists(dir / output, ec))
    drawn = Status::Failure("gnuplot drew nothing from " + (dir / script_name).string(), ErrorCode::kInternal);
  if (!drawn) {
    fs::remove(dir / output, ec);
    // The data is there without gnuplot, but not on a disk that takes no more.
    if (drawn.code() == ErrorCode::kIo) {
      fs::remove(dir / script_name, ec);
      return Error{ErrorCode::kIo, (dir / output).string() +
                                       ": cannot write the plot (the disk is full or a file-size limit was reached)"};
    }
    return R(std::optional<std::string>(drawn.error()));
  }
  return R(std::optional<std::string>());
}

}  // namespace shimmer
