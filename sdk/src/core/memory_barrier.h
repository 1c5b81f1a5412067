// A global memory barrier (no image or buffer range, no queue transfer): the dependency the SDK's buffer copies,
// fills and counter passes record.
#pragma once

#include "device_functions.h"

namespace rb {

inline void recordMemoryBarrier(const DeviceFunctions& vk, VkCommandBuffer cmd, VkPipelineStageFlags srcStages,
                                VkAccessFlags srcAccess, VkPipelineStageFlags dstStages, VkAccessFlags dstAccess) {
  VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  b.srcAccessMask = srcAccess;
  b.dstAccessMask = dstAccess;
  vk.vkCmdPipelineBarrier(cmd, srcStages, dstStages, 0, 1, &b, 0, nullptr, 0, nullptr);
}

}  // namespace rb
