// Turning VkResult failures into messages: internal code returns std::string errors (empty = ok).
#pragma once

#include <string>

#include <vulkan/vulkan.h>

namespace sample_engine::detail {

std::string vkResultName(VkResult r);

inline std::string vkFailure(const char* what, VkResult r) {
  std::string message = std::string(what) + " failed: " + vkResultName(r);
  if (r == VK_ERROR_DEVICE_LOST) {
    message += " (device lost: the GPU stopped executing this device's work, e.g. after a fault, a hang or a driver "
               "reset; nothing more can be rendered with it: destroy the engine and create a new one)";
  }
  return message;
}

}  // namespace sample_engine::detail

// Evaluates a Vulkan call; on failure returns (from the enclosing function) an error string or Status.
#define SE_VK_TRY(call)                                                                               \
  do {                                                                                                \
    VkResult se_vk_result_ = (call);                                                                  \
    if (se_vk_result_ != VK_SUCCESS) return ::sample_engine::detail::vkFailure(#call, se_vk_result_); \
  } while (0)
