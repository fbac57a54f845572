#include "commands.h"

namespace shimmer::cli {

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
  if (used != value.size()) throw UsageError("--param " + name + ": '" + value + "' is not a number");
  return {name, v};
}

}  // namespace shimmer::cli
