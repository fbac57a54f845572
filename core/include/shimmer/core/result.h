// Errors at every library boundary are values: a Result holds either a value
// or an Error, one message that names the file or field and the problem, with
// a code that says what kind of failure it is. Only the CLI turns an Error
// into its single error line and exit status (bad input: 2, anything else: 1).
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace shimmer {

enum class ErrorCode {
  kBadInput,     // the user's input is wrong: a value, a file's contents, a name
  kIo,           // reading or writing failed: missing permission, full disk
  kDeviceLost,   // the GPU stopped answering (reset, hang, driver crash)
  kOutOfMemory,  // host or device memory ran out
  kBusy,         // another process holds what is needed (a store's lock); the same command works later
  kInternal,     // a failure no input explains (a bug, or the platform)
};

// "bad input", "I/O error", ...
const char* ErrorCodeName(ErrorCode code);

struct Error {
  ErrorCode code = ErrorCode::kInternal;
  std::string message;
};

template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : value_(std::move(value)) {}      // NOLINT: implicit on purpose, `return value;`
  Result(Error error) : error_(std::move(error)) {}  // NOLINT: `return other.failure();`
  static Result Failure(std::string message, ErrorCode code = ErrorCode::kBadInput) {
    return Result(Error{code, std::move(message)});
  }

  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  const std::string& error() const { return error_.message; }
  ErrorCode code() const { return error_.code; }
  const Error& failure() const { return error_; }

  T& value() { return *value_; }
  const T& value() const { return *value_; }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() { return *value_; }
  const T& operator*() const { return *value_; }

 private:
  std::optional<T> value_;
  Error error_;
};

// For operations whose only result is success or an Error.
struct Done {};
using Status = Result<Done>;
inline Status Ok() { return Done{}; }

// The error with `context + ": "` in front of its message, code kept.
inline Error Prefixed(const std::string& context, const Error& error) {
  return Error{error.code, context + ": " + error.message};
}

}  // namespace shimmer
