// Helpers every subcommand shares: --param values, flag names in library
// errors, output locations.
#include <cmath>
#include <filesystem>

#include "commands.h"

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
    throw UsageError(option + " " + path + ": the directory " + parent.string() + " does not exist");
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
