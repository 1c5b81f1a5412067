// Memory barriers without a queue transfer: a global one (the dependency the SDK's buffer copies, fills and counter
// passes record), and one over a whole buffer (the light list's upload, the many-light tile lists).
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

inline void recordBufferBarrier(const DeviceFunctions& vk, VkCommandBuffer cmd, VkBuffer buffer,
                                VkPipelineStageFlags srcStages, VkAccessFlags srcAccess, VkPipelineStageFlags dstStages,
                                VkAccessFlags dstAccess) {
  VkBufferMemoryBarrier b{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
  b.srcAccessMask = srcAccess;
  b.dstAccessMask = dstAccess;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.buffer = buffer;
  b.size = VK_WHOLE_SIZE;
  vk.vkCmdPipelineBarrier(cmd, srcStages, dstStages, 0, 0, nullptr, 1, &b, 0, nullptr);
}

}  // namespace rb
