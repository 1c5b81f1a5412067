// The per-context Vulkan function table. Raybridge never calls the loader's global entry points, so an engine
// that uses volk, its own loader or several devices keeps working (the volk habit).
#pragma once

#include <vulkan/vulkan_core.h>

namespace rb {

#define RB_INSTANCE_FUNCTIONS(X)              \
  X(vkGetDeviceProcAddr)                      \
  X(vkGetPhysicalDeviceProperties)            \
  X(vkGetPhysicalDeviceProperties2)           \
  X(vkGetPhysicalDeviceFeatures2)             \
  X(vkGetPhysicalDeviceMemoryProperties)      \
  X(vkGetPhysicalDeviceFormatProperties)      \
  X(vkGetPhysicalDeviceQueueFamilyProperties) \
  X(vkEnumerateDeviceExtensionProperties)

#define RB_DEVICE_FUNCTIONS(X)                                                \
  X(vkCreateBuffer)                                                           \
  X(vkDestroyBuffer)                                                          \
  X(vkGetBufferMemoryRequirements)                                            \
  X(vkBindBufferMemory)                                                       \
  X(vkAllocateMemory)                                                         \
  X(vkFreeMemory)                                                             \
  X(vkMapMemory)                                                              \
  X(vkUnmapMemory)                                                            \
  X(vkGetBufferDeviceAddress)                                                 \
  X(vkCreateImage)                                                            \
  X(vkDestroyImage)                                                           \
  X(vkGetImageMemoryRequirements)                                             \
  X(vkBindImageMemory)                                                        \
  X(vkCreateImageView)                                                        \
  X(vkDestroyImageView)                                                       \
  X(vkCreateSampler)                                                          \
  X(vkDestroySampler)                                                         \
  X(vkCreateQueryPool)                                                        \
  X(vkDestroyQueryPool)                                                       \
  X(vkGetQueryPoolResults)                                                    \
  X(vkCmdResetQueryPool)                                                      \
  X(vkCmdWriteTimestamp)                                                      \
  X(vkCmdPipelineBarrier)                                                     \
  X(vkCmdCopyBuffer)                                                          \
  X(vkCmdCopyImageToBuffer)                                                   \
  X(vkCmdCopyBufferToImage)                                                   \
  X(vkCmdFillBuffer)                                                          \
  X(vkCmdUpdateBuffer)                                                        \
  X(vkCmdClearColorImage)                                                     \
  X(vkCmdBindPipeline)                                                        \
  X(vkCmdPushConstants)                                                       \
  X(vkCmdDispatch)                                                            \
  X(vkCmdBindDescriptorSets)                                                  \
  X(vkCreateShaderModule)                                                     \
  X(vkDestroyShaderModule)                                                    \
  X(vkCreatePipelineLayout)                                                   \
  X(vkDestroyPipelineLayout)                                                  \
  X(vkCreateComputePipelines)                                                 \
  X(vkDestroyPipeline)                                                        \
  X(vkCreateDescriptorSetLayout)                                              \
  X(vkDestroyDescriptorSetLayout)                                             \
  X(vkCreateDescriptorPool)                                                   \
  X(vkDestroyDescriptorPool)                                                  \
  X(vkAllocateDescriptorSets)                                                 \
  X(vkUpdateDescriptorSets)                                                   \
  X(vkCreateAccelerationStructureKHR)                                         \
  X(vkDestroyAccelerationStructureKHR)                                        \
  X(vkGetAccelerationStructureBuildSizesKHR)                                  \
  X(vkGetAccelerationStructureDeviceAddressKHR)                               \
  X(vkCmdBuildAccelerationStructuresKHR)                                      \
  X(vkCmdCopyAccelerationStructureKHR)                                        \
  X(vkCmdWriteAccelerationStructuresPropertiesKHR)                            \
  X(vkCreateRayTracingPipelinesKHR)                                           \
  X(vkGetRayTracingShaderGroupHandlesKHR)                                     \
  X(vkCmdTraceRaysKHR)                                                        \
  X(vkCmdTraceRaysIndirectKHR)                                                \
  X(vkCmdPushDescriptorSetKHR)                                                \
  X(vkCreateCommandPool)                                                      \
  X(vkDestroyCommandPool)                                                     \
  X(vkAllocateCommandBuffers)                                                 \
  X(vkFreeCommandBuffers)                                                     \
  X(vkBeginCommandBuffer)                                                     \
  X(vkEndCommandBuffer)                                                       \
  X(vkResetCommandBuffer)                                                     \
  X(vkQueueSubmit) /* async BLAS builds only, on AsServiceDesc::asyncQueue */ \
  X(vkCreateSemaphore)                                                        \
  X(vkDestroySemaphore)                                                       \
  X(vkGetSemaphoreCounterValue)

struct DeviceFunctions {
#define RB_DECLARE(name) PFN_##name name = nullptr;
  RB_INSTANCE_FUNCTIONS(RB_DECLARE)
  RB_DEVICE_FUNCTIONS(RB_DECLARE)
#undef RB_DECLARE
};

// Loads every function; returns the name of the first one that is missing (nullptr when all loaded). A
// missing device function means the engine did not enable the extension that provides it.
const char* loadDeviceFunctions(DeviceFunctions& table, PFN_vkGetInstanceProcAddr getInstanceProcAddr,
                                VkInstance instance, VkDevice device);

}  // namespace rb
