#include <string>

#include "vulkan_errors.h"

namespace rb {

const char* toString(VkResult result) {
  switch (result) {
#define RB_CASE(r) \
  case r: return #r;
    RB_CASE(VK_SUCCESS)
    RB_CASE(VK_NOT_READY)
    RB_CASE(VK_TIMEOUT)
    RB_CASE(VK_INCOMPLETE)
    RB_CASE(VK_ERROR_OUT_OF_HOST_MEMORY)
    RB_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    RB_CASE(VK_ERROR_INITIALIZATION_FAILED)
    RB_CASE(VK_ERROR_DEVICE_LOST)
    RB_CASE(VK_ERROR_MEMORY_MAP_FAILED)
    RB_CASE(VK_ERROR_LAYER_NOT_PRESENT)
    RB_CASE(VK_ERROR_EXTENSION_NOT_PRESENT)
    RB_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
    RB_CASE(VK_ERROR_INCOMPATIBLE_DRIVER)
    RB_CASE(VK_ERROR_TOO_MANY_OBJECTS)
    RB_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED)
    RB_CASE(VK_ERROR_FRAGMENTED_POOL)
    RB_CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
    RB_CASE(VK_ERROR_INVALID_EXTERNAL_HANDLE)
    RB_CASE(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS)
    RB_CASE(VK_ERROR_UNKNOWN)
#undef RB_CASE
    default: return "VkResult(other)";
  }
}

Error vulkanError(VkResult result, const std::string& what) {
  return Error{ErrorCode::VulkanError, result,
               what + " failed: " + toString(result) + " (" + std::to_string(static_cast<int>(result)) + ")"};
}

}  // namespace rb
