// Instance, debug messenger, physical-device choice and device creation.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "sample_engine/engine.h"

namespace sample_engine::detail {

struct ValidationCounters {
  std::atomic<uint32_t> errors{0};
  std::atomic<uint32_t> warnings{0};
};

struct VulkanContext {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physicalDevice = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t queueFamily = 0;
  VkQueue asyncComputeQueue = VK_NULL_HANDLE;  // EngineConfig::requestAsyncComputeQueue and the device has one
  uint32_t asyncComputeFamily = UINT32_MAX;    // a COMPUTE family without GRAPHICS
  bool bufferDeviceAddressFeature = false;     // enabled (the deformation pass needs it), whatever
                                               // info.bufferDeviceAddress says about scene buffers
  DeviceInfo info;
  std::vector<std::string> deviceExtensions;
  bool swapchainEnabled = false;
  bool accelerationStructureEnabled = false;  // VK_KHR_acceleration_structure among the device extensions
  float timestampPeriodNs = 1.0f;
  bool timestampsSupported = false;
  VkPhysicalDeviceProperties properties{};
  // The frame loop's submit and fence wait: the loader's, or EngineConfig's test hooks.
  PFN_vkQueueSubmit2 queueSubmit2 = nullptr;
  PFN_vkWaitForFences waitForFences = nullptr;
  std::unique_ptr<ValidationCounters> counters = std::make_unique<ValidationCounters>();

  // Returns an error message, empty on success. On failure the partially created objects are destroyed
  // by destroy().
  std::string create(const EngineConfig& config);
  void destroy();
};

}  // namespace sample_engine::detail
