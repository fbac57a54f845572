// Errors at the library boundary are values: a Result holds either a value or
// one message that names the file and the problem. The CLI turns the message
// into its single error line; tests compare it.
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace shimmer::metrics {

template <class T>
class Result {
 public:
  Result(T value) : value_(std::move(value)) {}  // NOLINT: implicit on purpose, `return value;`
  static Result Failure(std::string message) {
    Result r;
    r.error_ = std::move(message);
    return r;
  }

  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  const std::string& error() const { return error_; }
  T& value() { return *value_; }
  const T& value() const { return *value_; }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() { return *value_; }
  const T& operator*() const { return *value_; }

 private:
  Result() = default;
  std::optional<T> value_;
  std::string error_;
};

// For operations whose only result is success or a message.
struct Done {};
using Status = Result<Done>;
inline Status Ok() { return Done{}; }

}  // namespace shimmer::metrics
