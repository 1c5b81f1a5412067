// Error reporting for the public API: nothing throws across it, every fallible call returns one of these.
#pragma once

#include <string>
#include <utility>

namespace sample_engine {

// Outcome of an operation without a value. An empty message means success.
struct Status {
  std::string error;

  bool ok() const { return error.empty(); }
  explicit operator bool() const { return ok(); }
  static Status success() { return {}; }
  static Status failure(std::string message) { return Status{message.empty() ? "unknown error" : std::move(message)}; }
};

// Outcome of an operation that produces a value; `value` is meaningful only when ok().
template <typename T>
struct Result {
  T value{};
  std::string error;

  bool ok() const { return error.empty(); }
  explicit operator bool() const { return ok(); }
  static Result failure(std::string message) {
    Result r;
    r.error = message.empty() ? "unknown error" : std::move(message);
    return r;
  }
  static Result success(T v) {
    Result r;
    r.value = std::move(v);
    return r;
  }
};

}  // namespace sample_engine
