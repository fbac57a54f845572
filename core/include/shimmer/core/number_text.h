// Numbers in messages: "%g", the short form a user reads ("1e+39", "0.25",
// "nan"), never std::to_string's "0.000000".
#pragma once

#include <cstdio>
#include <string>

namespace shimmer {

inline std::string NumberText(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

}  // namespace shimmer
