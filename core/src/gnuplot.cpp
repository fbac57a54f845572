#include "shimmer/core/gnuplot.h"

#include <cstdlib>

#include "shimmer/core/atomic_file.h"

namespace shimmer {

namespace fs = std::filesystem;

namespace {

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
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
  return Ok();
}

Result<std::optional<std::string>> WritePlot(const fs::path& dir, const std::string& script_name,
                                             const std::string& output,
                                             const std::function<std::string(const std::string&)>& script_text) {
  using R = Result<std::optional<std::string>>;
  if (Status s = WriteFileAtomic(dir / script_name, script_text(output)); !s) return s.failure();
  const fs::path partial_output = TemporaryPathFor(dir / output);
  const fs::path partial_script = TemporaryPathFor(dir / script_name);
  if (Status s = WriteFileAtomic(partial_script, script_text(partial_output.filename().string())); !s)
    return s.failure();
  Status drawn = RunGnuplot(dir, partial_script.filename().string());
  std::error_code ec;
  fs::remove(partial_script, ec);
  if (drawn && !fs::exists(partial_output, ec))
    drawn = Status::Failure("gnuplot drew nothing from " + (dir / script_name).string(), ErrorCode::kInternal);
  if (!drawn) {
    fs::remove(partial_output, ec);
    return R(std::optional<std::string>(drawn.error()));
  }
  if (Status s = CommitFile(partial_output, dir / output); !s) return s.failure();
  return R(std::optional<std::string>());
}

}  // namespace shimmer
