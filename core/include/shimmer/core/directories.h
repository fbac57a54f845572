// Output directories: what creating one would make, and whether it can be
// made, so that a command refuses an output location before any work and
// removes again exactly the directories it created.
#pragma once

#include <filesystem>
#include <vector>

#include "shimmer/core/result.h"

namespace shimmer {

// The directories that creating `dir` would make, deepest first: `dir` and
// each missing parent. Empty when `dir` exists.
std::vector<std::filesystem::path> MissingDirectories(const std::filesystem::path& dir);

// Whether `dir` exists as a directory, or can be created, and be written
// into: its nearest existing ancestor must be a directory (else bad input:
// "<ancestor> is not a directory") that this process may write (else an I/O
// error: "cannot write into <ancestor> (<reason>)").
Status CheckCreatableDirectory(const std::filesystem::path& dir);

}  // namespace shimmer
