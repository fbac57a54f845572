// Helpers every subcommand shares: --param values, flag names in library
// errors, output locations.
#include <cctype>
#include <cmath>
#include <filesystem>

#include "commands.h"
#include "shimmer/core/directories.h"
#include "shimmer/shading/shading.h"

namespace shimmer::cli {

Error WithFlagNames(const Error& error, const FieldFlags& fields) {
  for (const auto& [field, flag] : fields)
    if (error.message.rfind(field, 0) == 0) return Error{error.code, flag + error.message.substr(field.size())};
  return error;
}

scene::CameraPath CameraPathOption(const std::string& name) {
  if (const auto path = scene::ParseCameraPath(name)) return *path;
  std::string list;
  for (auto n : scene::CameraPathNames()) list += (list.empty() ? "" : ", ") + std::string(n);
  throw UsageError("--camera must be one of " + list + ", got '" + name + "'");
}

void RequireParentDirectory(const std::string& option, const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::exists(parent, ec))
    throw UsageError(option + " " + path + ": " + parent.string() + ": the directory does not exist");
  if (Status s = CheckCreatableDirectory(parent); !s) throw CommandError(Prefixed(option + " " + path, s.failure()));
}

void RequireCreatableDirectory(const std::string& option, const std::string& path) {
  // Found before the work: a file in the way is bad input, a directory the
  // user may not write to the system's answer.
  if (Status s = CheckCreatableDirectory(path); !s) throw CommandError(Prefixed(option + " " + path, s.failure()));
}

NewDirectories::~NewDirectories() {
  std::error_code ec;
  for (auto it = created_.rbegin(); it != created_.rend(); ++it)
    with_contents_ ? std::filesystem::remove_all(*it, ec) : std::filesystem::remove(*it, ec);  // else only when empty
}

void NewDirectories::Create(const std::string& what, const std::filesystem::path& dir) {
  const std::vector<std::filesystem::path> missing = MissingDirectories(dir);  // deepest first
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  // Those made before a failure are removed with the rest.
  created_.insert(created_.end(), missing.rbegin(), missing.rend());
  if (!ec) return;
  const std::error_code failure = ec;
  const std::vector<std::filesystem::path> still_missing = MissingDirectories(dir);
  const std::filesystem::path blocking = still_missing.empty() ? dir : still_missing.back().parent_path();
  if (failure == std::errc::not_a_directory || failure == std::errc::file_exists)
    throw UsageError(what + ": " + blocking.string() + " is not a directory");
  throw CommandError(
      Error{ErrorCode::kIo, what + ": cannot create the directory " + dir.string() + " (" + failure.message() + ")"});
}

void RequireOneFilter(const CLI::App& cmd, const std::string& variant, const std::string& variant_file) {
  if (!variant_file.empty() && cmd.count("--variant") > 0)
    throw UsageError("--variant " + variant + " and --variant-file " + variant_file + " both name the filter; give one");
}

std::string UserVariantName(const std::string& file) {
  std::string name = std::filesystem::path(file).stem().string();
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  if (name.empty() || name.front() == '.') name = "user" + name;
  if (name.size() > 64) name.resize(64);
  // A file called tk19.glsl must not pass for the built-in tk19.
  if (shading::ParseVariantName(name)) name += "-file";
  return name;
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
