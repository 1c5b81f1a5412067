// Rounding a size or offset up to an alignment: buffer offsets, scratch and shader-table strides.
#pragma once

#include <vulkan/vulkan_core.h>

namespace rb {

// `v` rounded up to a multiple of `alignment` (> 0; need not be a power of two).
inline VkDeviceSize alignUp(VkDeviceSize v, VkDeviceSize alignment) {
  return (v + alignment - 1) / alignment * alignment;
}

}  // namespace rb
