// The version of the code that turns frames into numbers: a hash of the
// metrics library's sources and the EXR reader, made at build time. A stored
// row measured by other code has another id (experiments/jobs/job.cpp);
// comments and white space are not part of it (cmake/HashFilesScript.cmake).
#pragma once

#include <string_view>

namespace shimmer::metrics {

std::string_view MetricsCodeVersion();
// The sparkle statistics' own code (sparkle_statistics.h, .cpp): only rows
// that compute them carry it.
std::string_view SparkleCodeVersion();

}  // namespace shimmer::metrics
