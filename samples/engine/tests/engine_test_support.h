// Helpers shared by the engine's test files: the validated engine, the shared models, and an external
// lighting-input image filled from the pre-pass hook.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <memory>

#include <catch2/catch_test_macros.hpp>
#include <glm/glm.hpp>

#include "sample_engine/engine.h"

namespace test_support {

// An engine with validation on (tests assert validationErrorCount() == 0 at the end).
inline std::unique_ptr<sample_engine::Engine> makeEngine(sample_engine::EngineConfig config = {}) {
  config.enableValidation = true;
  auto r = sample_engine::Engine::create(config);
  INFO(r.error);
  REQUIRE(r.ok());
  return std::move(r.value);
}

// The shared glTF sample models: $RAYBRIDGE_SCENES, else ../shared/scenes beside the source tree.
inline std::filesystem::path sharedScenesDir() {
  if (const char* env = std::getenv("RAYBRIDGE_SCENES"); env && *env) return env;
  return std::filesystem::path(RAYBRIDGE_SOURCE_DIR) / ".." / "shared" / "scenes";
}

// A screen-sized image (R8 by default) the test owns and fills from inside the pre-pass hook, the way an
// add-on would.
struct ExternalMask {
  VkDevice device = VK_NULL_HANDLE;
  VkImage image = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;

  ExternalMask(sample_engine::Engine& engine, uint32_t w, uint32_t h, VkFormat format = VK_FORMAT_R8_UNORM)
      : device(engine.device()) {
    VkImageCreateInfo ci{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    ci.imageType = VK_IMAGE_TYPE_2D;
    ci.format = format;
    ci.extent = {w, h, 1};
    ci.mipLevels = ci.arrayLayers = 1;
    ci.samples = VK_SAMPLE_COUNT_1_BIT;
    ci.tiling = VK_IMAGE_TILING_OPTIMAL;
    ci.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    REQUIRE(vkCreateImage(device, &ci, nullptr, &image) == VK_SUCCESS);
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(device, image, &req);
    VkPhysicalDeviceMemoryProperties props;
    vkGetPhysicalDeviceMemoryProperties(engine.physicalDevice(), &props);
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    for (uint32_t i = 0; i < props.memoryTypeCount; ++i)
      if (req.memoryTypeBits & (1u << i)) {
        ai.memoryTypeIndex = i;
        break;
      }
    REQUIRE(vkAllocateMemory(device, &ai, nullptr, &memory) == VK_SUCCESS);
    REQUIRE(vkBindImageMemory(device, image, memory, 0) == VK_SUCCESS);
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    REQUIRE(vkCreateImageView(device, &vi, nullptr, &view) == VK_SUCCESS);
  }
  ~ExternalMask() {
    vkDeviceWaitIdle(device);
    vkDestroyImageView(device, view, nullptr);
    vkDestroyImage(device, image, nullptr);
    vkFreeMemory(device, memory, nullptr);
  }

  // Records a clear to `value` (all channels) and leaves the image in SHADER_READ_ONLY_OPTIMAL.
  void record(VkCommandBuffer cmd, float value) const { record(cmd, glm::vec4(value)); }
  void record(VkCommandBuffer cmd, glm::vec4 value) const {
    VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
    b.srcStageMask = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;  // previous frame's lighting pass read it
    b.dstStageMask = VK_PIPELINE_STAGE_2_CLEAR_BIT;
    b.dstAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.imageMemoryBarrierCount = 1;
    dep.pImageMemoryBarriers = &b;
    vkCmdPipelineBarrier2(cmd, &dep);
    VkClearColorValue color{{value.r, value.g, value.b, value.a}};
    vkCmdClearColorImage(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &color, 1, &b.subresourceRange);
    b.srcStageMask = VK_PIPELINE_STAGE_2_CLEAR_BIT;
    b.srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT;
    b.dstStageMask = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;
    b.dstAccessMask = VK_ACCESS_2_SHADER_SAMPLED_READ_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    vkCmdPipelineBarrier2(cmd, &dep);
  }
};

}  // namespace test_support
