#include "output_files.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

namespace shimmer::experiments {

namespace fs = std::filesystem;

std::string WriteFileAtomic(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << text;
    if (!out) return tmp.string() + ": cannot write";
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  return ec ? path.string() + ": " + ec.message() : "";
}

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

void RunGnuplot(const fs::path& dir, const std::vector<std::string>& scripts, std::vector<std::string>* warnings) {
  const std::string where = dir.empty() ? std::string(".") : dir.string();
  for (const std::string& s : scripts) {
    const std::string cmd = "cd '" + where + "' && gnuplot '" + s + "' 2>/dev/null";
    if (std::system(cmd.c_str()) != 0 && warnings) warnings->push_back("gnuplot failed or is missing: " + s);
  }
}

}  // namespace shimmer::experiments
