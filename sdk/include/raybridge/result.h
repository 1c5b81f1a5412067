// Raybridge results: every fallible call returns a value or an error code with a message naming the bad input.
// No exception ever crosses the public API.
// Thread safety: Result and Error are plain values; distinct objects may be used from any thread.
#pragma once

#include <vulkan/vulkan_core.h>

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
};

// A human-readable name for an error code, e.g. "InvalidArgument".
const char* toString(ErrorCode code);

struct Error {
  ErrorCode code = ErrorCode::Ok;
  VkResult vkResult = VK_SUCCESS;  // the failing Vulkan result for ErrorCode::VulkanError, else VK_SUCCESS
  std::string message;             // what went wrong and what to do about it
};

// Either a T or an Error. Check ok() (or operator bool) before value().
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::move(value)) {}
  Result(Error error) : state_(std::move(error)) {}

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }
  T& value() & { return std::get<0>(state_); }
  const T& value() const& { return std::get<0>(state_); }
  T&& value() && { return std::get<0>(std::move(state_)); }
  const Error& error() const { return std::get<1>(state_); }
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

 private:
  Error error_;
};

}  // namespace rb
