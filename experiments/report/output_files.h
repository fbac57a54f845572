// Writing report artefacts: files replaced atomically (a temporary name, then
// a rename, so an interrupted report never leaves half a table), file-name
// slugs, number formatting, and gnuplot runs.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace shimmer::experiments {

// Writes `text` to `path` via `path.tmp` and a rename; returns an error message, empty on success.
std::string WriteFileAtomic(const std::filesystem::path& path, const std::string& text);

// Letters and digits kept, everything else '_': a safe file-name stem.
std::string Slug(const std::string& s);

// printf-style, with "–" for NaN.
std::string FormatNumber(double v, const char* format = "%.4g");

// Runs each script with gnuplot inside `dir`; a failure (or no gnuplot) adds
// a warning naming the script, whose data stay ready to plot.
void RunGnuplot(const std::filesystem::path& dir, const std::vector<std::string>& scripts,
                std::vector<std::string>* warnings);

}  // namespace shimmer::experiments
