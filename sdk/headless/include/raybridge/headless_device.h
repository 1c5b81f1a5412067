// A headless Vulkan device for Raybridge's samples, tests and benchmarks: it plays the engine's part
// (instance, device, queue, an optional async compute queue, one-shot submissions). Engines that have their own
// device do not need it. It is its own library, Raybridge::headless (target raybridge_headless): the core
// Raybridge library never creates a device, submits, waits or opens the loader.
//
// Device choice: a GPU with ray tracing pipelines if there is one, otherwise a CPU implementation (lavapipe).
// `HeadlessDeviceDesc::deviceNameFilter` or the environment variable RAYBRIDGE_DEVICE (a case-insensitive
// substring of the device name, e.g. "llvmpipe" or "H100") overrides the choice.
//
// Thread safety: not thread-safe; use one HeadlessDevice from one thread at a time. Except: its validation
// messages arrive on whichever thread calls Vulkan on the device (e.g. AccelerationStructureService::registerMesh
// on a streaming thread), so validationErrorCount() and validationErrors() may be called from any thread.
#pragma once

#include <raybridge/context.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace rb {

struct HeadlessDeviceDesc {
  const char* deviceNameFilter = nullptr;  // nullptr = $RAYBRIDGE_DEVICE if set, else automatic choice
  bool enableValidation = false;  // VK_LAYER_KHRONOS_validation + debug messenger; also on when $RAYBRIDGE_VALIDATION=1
  bool requireValidation = false;  // fail creation when validation was asked for but the layer is missing
  uint32_t framesInFlight = 0;     // 0 = 2; copied into contextDesc()
  // Also create one queue of a family with VK_QUEUE_COMPUTE_BIT and no VK_QUEUE_GRAPHICS_BIT, when the device
  // has one (GPUs usually do; lavapipe does not), for AsServiceDesc::asyncQueue. Then every buffer the device
  // creates is VK_SHARING_MODE_CONCURRENT over both families. false = one queue.
  bool requestAsyncComputeQueue = false;
  // false = enable VK_NV_ray_tracing_invocation_reorder and its feature where the device supports them
  // (rb::supportsInvocationReorder), and say so in contextDesc(); true = never (a device like the engine's that
  // did not enable it).
  bool disableInvocationReorder = false;
};

// A buffer made by the headless device for samples and tests (the engine's buffers in a real integration).
struct HeadlessBuffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceAddress address = 0;  // 0 unless created with VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT
  VkDeviceSize size = 0;
  void* mapped = nullptr;  // non-null for host-visible buffers
};

class HeadlessDevice {
 public:
  static Result<std::unique_ptr<HeadlessDevice>> create(const HeadlessDeviceDesc& desc = {});
  ~HeadlessDevice();
  HeadlessDevice(const HeadlessDevice&) = delete;
  HeadlessDevice& operator=(const HeadlessDevice&) = delete;

  VkInstance instance() const;
  VkPhysicalDevice physicalDevice() const;
  VkDevice device() const;
  VkQueue queue() const;
  uint32_t queueFamily() const;
  // The compute queue of HeadlessDeviceDesc::requestAsyncComputeQueue; VK_NULL_HANDLE / UINT32_MAX when it was
  // not requested or the device has no compute-only family.
  VkQueue asyncComputeQueue() const;
  uint32_t asyncComputeQueueFamily() const;
  PFN_vkGetInstanceProcAddr getInstanceProcAddr() const;
  // Instance-level function loaded from the headless instance (handy for tests that call Vulkan directly).
  PFN_vkVoidFunction instanceProc(const char* name) const;
  PFN_vkVoidFunction deviceProc(const char* name) const;
  // Whether the device was created with VK_NV_ray_tracing_invocation_reorder (HeadlessDeviceDesc).
  bool invocationReorderEnabled() const;
  // A ContextDesc filled with this device's handles (and invocationReorderEnabled).
  ContextDesc contextDesc() const;
  std::string deviceName() const;

  // Validation messages of severity error seen since creation (always 0 when validation is off); a copy, as
  // another thread may be adding one.
  uint32_t validationErrorCount() const;
  std::vector<std::string> validationErrors() const;
  bool validationEnabled() const;

  // One-shot recording: beginCommands() returns a command buffer in the recording state; submitAndWait() ends,
  // submits and waits for it, then frees it.
  Result<VkCommandBuffer> beginCommands();
  Status submitAndWait(VkCommandBuffer cmd);
  // The same on queue(), with semaphore waits and signals (vkQueueSubmit2; timeline values in the infos).
  Status submitAndWait(VkCommandBuffer cmd, std::span<const VkSemaphoreSubmitInfo> waits,
                       std::span<const VkSemaphoreSubmitInfo> signals);

  // A timeline semaphore starting at 0 (the engine's side of AsyncBuildWait), and its destruction.
  Result<VkSemaphore> createTimelineSemaphore();
  void destroySemaphore(VkSemaphore semaphore);

  // Creates a buffer. Device-local unless hostVisible; `data` (size bytes) is uploaded through a staging copy
  // for device-local buffers and memcpy'd otherwise.
  Result<HeadlessBuffer> createBuffer(VkDeviceSize size, VkBufferUsageFlags usage, bool hostVisible,
                                      const void* data = nullptr);
  // Copies a device-local buffer's contents back to `out` (size bytes).
  Status readBuffer(const HeadlessBuffer& buffer, void* out, VkDeviceSize size);
  void destroyBuffer(HeadlessBuffer& buffer);
  Status waitIdle();

  struct Impl;

 private:
  explicit HeadlessDevice(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
