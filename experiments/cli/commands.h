// Each subcommand lives in its own file and registers itself on the app.
#pragma once

#include <CLI/CLI.hpp>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "shimmer/core/result.h"

#include "shimmer/experiments/runner.h"
#include "shimmer/renderer/scene.h"

namespace shimmer::cli {

// Thrown by a subcommand for bad input; main prints "shimmer: error: <what>"
// and exits with 2. Anything else that escapes exits with 1.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A library's Error on its way to main: exit 2 for bad input, 1 otherwise.
struct CommandError : std::runtime_error {
  CommandError(const Error& e) : std::runtime_error(e.message), code(e.code) {}  // NOLINT: implicit
  ErrorCode code;
};
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitFailure = 1;

// Library messages name fields ("width", "frames"); the CLI's user typed
// flags. Each (field, flag) pair rewrites a message that starts with the field.
using FieldFlags = std::vector<std::pair<std::string, std::string>>;
Error WithFlagNames(const Error& error, const FieldFlags& fields);

// The value of `result`, or a CommandError carrying its error.
template <class T>
T Take(Result<T> result, const FieldFlags& fields = {}) {
  if (!result) throw CommandError(WithFlagNames(result.failure(), fields));
  return std::move(*result);
}
inline void Check(const Status& status, const FieldFlags& fields = {}) {
  if (!status) throw CommandError(WithFlagNames(status.failure(), fields));
}

// Refuses to create an output file in a directory that does not exist: the
// user's typo would otherwise become a tree of new directories.
void RequireParentDirectory(const std::string& option, const std::string& path);
// For an output directory created with its parents: a file in the way is bad
// input, a directory the user may not write to an I/O error, both before the work.
void RequireCreatableDirectory(const std::string& option, const std::string& path);

// The directories a command creates for its outputs. Unless Keep() is called
// (the command succeeded), the destructor removes those still empty, deepest
// first: a command that fails leaves no empty directory behind. With
// `with_contents`, it removes them with whatever the command put in them.
class NewDirectories {
 public:
  explicit NewDirectories(bool with_contents = false) : with_contents_(with_contents) {}
  NewDirectories(const NewDirectories&) = delete;
  NewDirectories& operator=(const NewDirectories&) = delete;
  ~NewDirectories();
  // Creates `dir` and its missing parents, or throws a CommandError starting
  // with `what` (e.g. "--work x/y"): bad input when a file is in the way,
  // else an I/O error.
  void Create(const std::string& what, const std::filesystem::path& dir);
  void Keep() { created_.clear(); }

 private:
  std::vector<std::filesystem::path> created_;  // in creation order, parents first
  bool with_contents_;
};

// "--camera NAME" as a camera path; UsageError naming the paths for anything else.
scene::CameraPath CameraPathOption(const std::string& name);

// "--param name=value" as a (name, value) pair; UsageError for anything else.
std::pair<std::string, double> ParseParamOption(const std::string& text);
// --variant and --variant-file both given on `cmd`: a UsageError.
void RequireOneFilter(const CLI::App& cmd, const std::string& variant, const std::string& variant_file);

// The name a --variant-file's variant goes by in a spec, a sweep or a fit:
// the file's stem, made a valid variant name ("-file" added when it would
// be a built-in's).
std::string UserVariantName(const std::string& file);

// Fills db_path and work_dir: the given paths, else runs/<spec>/<db_file> and
// runs/<spec>/frames; creates their directories in `dirs`.
void StorePaths(const std::string& spec_name, const std::string& db, const std::string& work,
                const std::string& db_file, experiments::RunOptions* ro, NewDirectories* dirs);

void AddVariantsCommand(CLI::App& app);
void AddVideoCommand(CLI::App& app);
void AddNdfCommand(CLI::App& app);
void AddRenderCommand(CLI::App& app);
void AddMetricsCommand(CLI::App& app);
void AddRunCommand(CLI::App& app);
void AddMergeCommand(CLI::App& app);
void AddPruneCommand(CLI::App& app);
void AddSweepCommand(CLI::App& app);
void AddReportCommand(CLI::App& app);
void AddFitCommand(CLI::App& app);
void AddExportBlenderCommand(CLI::App& app);
void AddSgAccuracyCommand(CLI::App& app);
void AddSceneCommand(CLI::App& app);

}  // namespace shimmer::cli
