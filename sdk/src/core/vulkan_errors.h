// Names of Vulkan results (and, through vulkan_formats.h, of formats), and the Error of a failed Vulkan call
// (shared by the core and the headless device helper).
#pragma once

#include <raybridge/result.h>

#include <string>

#include "vulkan_formats.h"

namespace rb {

// Builds an Error for a failed Vulkan call: "<what> failed: VK_ERROR_... ".
Error vulkanError(VkResult result, const std::string& what);
const char* toString(VkResult result);

}  // namespace rb
