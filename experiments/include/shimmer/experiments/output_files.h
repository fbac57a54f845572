// Writing report artefacts: file-name slugs, number formatting, gnuplot text.
// A report's files appear together or not at all: shimmer/core/staged_directory.h.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "shimmer/core/result.h"
#include "shimmer/core/staged_directory.h"

namespace shimmer::experiments {

// Letters and digits kept, everything else '_': a safe file-name stem.
std::string Slug(const std::string& s);

// printf-style, with "–" for NaN.
std::string FormatNumber(double v, const char* format = "%.4g");

// gnuplot text in single quotes ('' for a quote), e.g. a title.
std::string GnuplotString(std::string_view text);

}  // namespace shimmer::experiments
