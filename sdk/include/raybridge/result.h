// Raybridge results: every fallible call returns a value or an error code with a message naming the bad input.
// No exception ever crosses the public API.
// Thread safety: Result and Error are plain values; distinct objects may be used from any thread.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <variant>

namespace rb {

enum class ErrorCode {
  Ok = 0,
  InvalidArgument,   // a description field is out of range or inconsistent; the message names the field
  MissingExtension,  // the device lacks a required extension; the message lists them by name
  MissingFeature,    // the device lacks a required feature; the message lists them by name
  NoSuitableDevice,  // no physical device satisfies the request
  VulkanError,       // a Vulkan call failed; Error::vkResult holds its result
  OutOfBudget,       // a memory budget declared by the engine cannot hold the request
  StaleHandle,       // a handle refers to a destroyed or released object
  NotReady,          // the object exists but is not usable yet (for example a BLAS still building)
  // The engine's Vulkan API version is below what Raybridge needs (1.2): ContextDesc::apiVersion, or a device
  // whose Vulkan 1.2 features all read as unsupported, which is what an instance created with
  // VkApplicationInfo::apiVersion 1.0 or 1.1 reports. The message says what to change.
  UnsupportedApiVersion,
};

// A human-readable name for an error code, e.g. "InvalidArgument".
const char* toString(ErrorCode code);

struct Error {
  ErrorCode code = ErrorCode::Ok;
  VkResult vkResult = VK_SUCCESS;  // the failing Vulkan result for ErrorCode::VulkanError, else VK_SUCCESS
  std::string message;             // what went wrong and what to do about it
};

namespace detail {
// value() on an error: the error is printed, never lost, and the program stops there (no exception crosses the
// API, and no undefined behaviour follows). Check ok() first where an error is expected.
[[noreturn]] inline void valueOfError(const Error& e) {
  std::fprintf(stderr, "raybridge: value() called on an error result: %s: %s\n", toString(e.code), e.message.c_str());
  std::fflush(stderr);
  std::abort();
}
inline const Error& okError() {
  static const Error ok{};
  return ok;
}
}  // namespace detail

// Either a T or an Error. The usual use:
//   auto ctx = rb::Context::create(desc);
//   if (!ctx) { log("Raybridge: %s", ctx.what()); return false; }   // what(): the message naming field and fix
//   std::unique_ptr<rb::Context> context = std::move(ctx).value();
// value() is checked: on an error it prints the error's code and message to stderr and aborts, so an unchecked
// value() in copied code still says what went wrong.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::move(value)) {}
  Result(Error error) : state_(std::move(error)) {}

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }
  T& value() & {
    if (!ok()) detail::valueOfError(error());
    return std::get<0>(state_);
  }
  const T& value() const& {
    if (!ok()) detail::valueOfError(error());
    return std::get<0>(state_);
  }
  T&& value() && {
    if (!ok()) detail::valueOfError(error());
    return std::get<0>(std::move(state_));
  }
  // The error; an Error with ErrorCode::Ok and no message when the result holds a value.
  const Error& error() const { return ok() ? detail::okError() : std::get<1>(state_); }
  // The error's message ("" when ok()): what went wrong, the field and the fix.
  const char* what() const { return error().message.c_str(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

 private:
  std::variant<T, Error> state_;
};

// The result of a call that returns nothing but can fail.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)) {}
  bool ok() const { return error_.code == ErrorCode::Ok; }
  explicit operator bool() const { return ok(); }
  const Error& error() const { return error_; }
  const char* what() const { return error_.message.c_str(); }  // "" when ok()

 private:
  Error error_;
};

}  // namespace rb
