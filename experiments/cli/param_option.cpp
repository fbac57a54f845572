// Helpers every subcommand shares: --param values, flag names in library
// errors, output locations.
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <filesystem>

#include "commands.h"
#include "shimmer/core/atomic_file.h"

namespace shimmer::cli {

Error WithFlagNames(const Error& error, const FieldFlags& fields) {
  for (const auto& [field, flag] : fields)
    if (error.message.rfind(field, 0) == 0) return Error{error.code, flag + error.message.substr(field.size())};
  return error;
}

void RequireParentDirectory(const std::string& option, const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
    throw UsageError(option + " " + path + ": " + parent.string() +
                     (std::filesystem::exists(parent, ec) ? " is not a directory" : ": the directory does not exist"));
  // Also found before the work: a directory the user may not write to is the system's answer, not bad input.
  const std::string dir = parent.empty() ? "." : parent.string();
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw CommandError(
        Error{ErrorCode::kIo, option + " " + path + ": cannot write into " + dir + " (" + SystemReason(errno) + ")"});
}

void RequireCreatableDirectory(const std::string& option, const std::string& path) {
  std::error_code ec;
  std::filesystem::path existing = path;
  while (!existing.empty() && !std::filesystem::exists(existing, ec) && existing != existing.parent_path())
    existing = existing.parent_path();
  const std::string dir = existing.empty() ? "." : existing.string();
  if (!std::filesystem::is_directory(dir, ec))
    throw UsageError(option + " " + path + ": " + dir + " is not a directory");
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw CommandError(
        Error{ErrorCode::kIo, option + " " + path + ": cannot write into " + dir + " (" + SystemReason(errno) + ")"});
}

NewDirectories::~NewDirectories() {
  std::error_code ec;
  for (auto it = created_.rbegin(); it != created_.rend(); ++it)
    with_contents_ ? std::filesystem::remove_all(*it, ec) : std::filesystem::remove(*it, ec);  // else only when empty
}

void NewDirectories::Create(const std::string& what, const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> missing;  // deepest first
  std::error_code ec;
  for (std::filesystem::path p = dir; !p.empty() && !std::filesystem::exists(p, ec) && p != p.parent_path();
       p = p.parent_path())
    missing.push_back(p);
  std::filesystem::create_directories(dir, ec);
  // Those made before a failure are removed with the rest.
  created_.insert(created_.end(), missing.rbegin(), missing.rend());
  if (!ec) return;
  const std::error_code failure = ec;
  std::filesystem::path blocking = dir;
  while (!blocking.empty() && !std::filesystem::exists(blocking, ec) && blocking != blocking.parent_path())
    blocking = blocking.parent_path();
  if (failure == std::errc::not_a_directory || failure == std::errc::file_exists)
    throw UsageError(what + ": " + blocking.string() + " is not a directory");
  throw CommandError(
      Error{ErrorCode::kIo, what + ": cannot create the directory " + dir.string() + " (" + failure.message() + ")"});
}

std::pair<std::string, double> ParseParamOption(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw UsageError("--param expects name=value, got '" + text + "'");
  const std::string name = text.substr(0, eq);
  const std::string value = text.substr(eq + 1);
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != value.size() || !std::isfinite(v))
    throw UsageError("--param " + name + ": '" + value + "' is not a finite number");
  return {name, v};
}

}  // namespace shimmer::cli
