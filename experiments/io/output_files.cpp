#include "shimmer/experiments/output_files.h"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>

#include "shimmer/core/atomic_file.h"

namespace shimmer::experiments {

namespace fs = std::filesystem;

std::string Slug(const std::string& s) {
  std::string out;
  for (char c : s) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out;
}

std::string FormatNumber(double v, const char* format) {
  if (std::isnan(v)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string GnuplotString(std::string_view text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

}  // namespace shimmer::experiments
