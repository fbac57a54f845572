// A set of output files that appear together or not at all.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "shimmer/core/result.h"

namespace shimmer {

// Files written into a hidden staging directory inside `out` and moved into
// `out` by Commit(), `last` after every other: a set of outputs (a report, metric maps) that fails (a full
// disk, a write error) or is interrupted leaves the previous report as it
// was, never half of a new one. Plot scripts run inside the staging
// directory and name their outputs by their final names.
class StagedDirectory {
 public:
  static Result<std::unique_ptr<StagedDirectory>> Create(const std::filesystem::path& out);
  ~StagedDirectory();  // removes what was not committed
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  const std::filesystem::path& staging() const { return staging_; }
  Status Write(const std::string& name, std::string_view text);
  // Moves every staged file into `out`; `last` (e.g. "report.md") goes last.
  Status Commit(const std::string& last);
  // `error` naming the files by their final paths, not the staging ones.
  Error Unstaged(const Error& error) const;

 private:
  StagedDirectory(std::filesystem::path out, std::filesystem::path staging, std::vector<std::filesystem::path> created)
      : out_(std::move(out)), staging_(std::move(staging)), created_(std::move(created)) {}
  std::filesystem::path out_, staging_;
  std::vector<std::filesystem::path> created_;  // `out` and the parents Create made, deepest first
  bool committed_ = false;
};

}  // namespace shimmer
