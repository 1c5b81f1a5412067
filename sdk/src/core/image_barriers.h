// The image barrier every pass records: whole colour image, one mip, one layer, no queue transfer.
#pragma once

#include <vulkan/vulkan_core.h>

namespace rb {

inline VkImageMemoryBarrier colorImageBarrier(VkImage image, VkImageLayout from, VkImageLayout to,
                                              VkAccessFlags srcAccess, VkAccessFlags dstAccess) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = srcAccess;
  b.dstAccessMask = dstAccess;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  return b;
}

}  // namespace rb
