// Buffers and images with their memory, allocated through the context's table and counted per category.
#pragma once

#include <raybridge/context.h>

#include <span>

namespace rb {

enum class MemoryLocation : uint8_t {
  DeviceLocal,  // fastest for the GPU
  HostVisible,  // host-visible and coherent, persistently mapped (upload rings, readback)
  // Host-visible and coherent, persistently mapped, in device-local memory where the device has such a type (a
  // BAR heap on a discrete GPU), else as HostVisible: small tables the host writes once and every ray reads (shader
  // binding tables, materials), so that those reads do not cross the bus.
  HostVisibleDeviceLocal,
};

struct GpuBuffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceAddress address = 0;  // set when usage includes SHADER_DEVICE_ADDRESS
  VkDeviceSize size = 0;        // requested size
  VkDeviceSize allocatedBytes = 0;
  void* mapped = nullptr;
  MemoryCategory category = MemoryCategory::PassBuffers;
  uint32_t owner = 0;  // Context::Impl::memoryOwner when created
  bool valid() const { return buffer != VK_NULL_HANDLE; }
};

struct GpuImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  uint32_t width = 0, height = 0;
  VkDeviceSize allocatedBytes = 0;
  MemoryCategory category = MemoryCategory::PassImages;
  uint32_t owner = 0;  // Context::Impl::memoryOwner when created
  bool valid() const { return image != VK_NULL_HANDLE; }
};

// `sharedWith`: two or more queue families make the buffer VK_SHARING_MODE_CONCURRENT over them (a buffer both
// the main and the async queue touch needs no ownership transfers); empty = exclusive.
Result<GpuBuffer> createBuffer(Context& ctx, VkDeviceSize size, VkBufferUsageFlags usage, MemoryLocation location,
                               MemoryCategory category, const char* what, std::span<const uint32_t> sharedWith = {});
// Destroys now. Use retireBuffer() when the GPU may still read it.
void destroyBuffer(Context& ctx, GpuBuffer& buffer);
// Destroys once the frames in flight that may use it are done (Context::beginFrame contract).
void retireBuffer(Context& ctx, GpuBuffer& buffer);

// A 2D storage + sampled image with one mip and its view, left in VK_IMAGE_LAYOUT_UNDEFINED.
Result<GpuImage> createStorageImage(Context& ctx, uint32_t width, uint32_t height, VkFormat format,
                                    VkImageUsageFlags extraUsage, MemoryCategory category, const char* what);
void destroyImage(Context& ctx, GpuImage& image);
void retireImage(Context& ctx, GpuImage& image);

}  // namespace rb
