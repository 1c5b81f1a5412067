// Buffers, images and one-shot command submission. Targets and small buffers get one VkDeviceMemory each;
// scene buffers (thousands with K animated characters) are bound into a few shared blocks by createBuffers(),
// staying far below maxMemoryAllocationCount.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

namespace sample_engine::detail {

struct Buffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceSize size = 0;
  void* mapped = nullptr;       // persistently mapped when host visible
  VkDeviceAddress address = 0;  // when created with SHADER_DEVICE_ADDRESS usage
};

struct Image {
  VkImage image = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkImageView altView = VK_NULL_HANDLE;  // e.g. the sRGB view of a mutable-format texture
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{};
  uint32_t mipLevels = 1;
  uint32_t layers = 1;
};

struct ImageDesc {
  VkFormat format;
  VkExtent2D extent;
  VkImageUsageFlags usage;
  VkImageAspectFlags aspect = VK_IMAGE_ASPECT_COLOR_BIT;
  uint32_t mipLevels = 1;
  VkFormat altViewFormat = VK_FORMAT_UNDEFINED;  // creates a MUTABLE_FORMAT image with a second view
  bool cube = false;         // 6 layers, CUBE_COMPATIBLE, `view` is a cube view (per-face views are the caller's)
  uint32_t arrayLayers = 0;  // (not cube) 0 = a plain 2D image; else that many layers and a 2D-array `view`
};

// One device-local buffer of a Gpu::createBuffers() batch.
struct BufferRequest {
  VkDeviceSize size = 0;
  VkBufferUsageFlags usage = 0;
  Buffer* out = nullptr;
  std::span<const uint32_t> queueFamilies;  // two or more: VK_SHARING_MODE_CONCURRENT over them
};

class Gpu {
 public:
  void init(VkPhysicalDevice pd, VkDevice device, VkQueue queue, uint32_t family);
  void shutdown();
  VkDevice device() const { return device_; }

  std::string createBuffer(VkDeviceSize size, VkBufferUsageFlags usage, VkMemoryPropertyFlags props, Buffer& out);
  // Device-local buffers bound into shared memory blocks, appended to `blocks` (freed with freeBlocks() after
  // the buffers are destroyed; the buffers' own `memory` stays VK_NULL_HANDLE).
  std::string createBuffers(std::span<const BufferRequest> requests, std::vector<VkDeviceMemory>& blocks);
  void freeBlocks(std::vector<VkDeviceMemory>& blocks);
  std::string createImage(const ImageDesc& desc, Image& out);
  void destroy(Buffer& b);
  void destroy(Image& i);

  // Records with `record` into a fresh command buffer, submits it on the queue and waits.
  template <typename F>
  std::string submitNow(F&& record) {
    VkCommandBuffer cmd;
    if (std::string e = beginOneShot(cmd); !e.empty()) return e;
    record(cmd);
    return endOneShot(cmd);
  }

 private:
  std::string beginOneShot(VkCommandBuffer& cmd);
  std::string endOneShot(VkCommandBuffer cmd);
  uint32_t memoryType(uint32_t bits, VkMemoryPropertyFlags props) const;

  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memProps_{};
};

// Synchronization2 image barrier over all mips/layers of `image`, or over mips [baseMip, baseMip+mipCount).
void imageBarrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout oldLayout,
                  VkImageLayout newLayout, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                  VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess, uint32_t baseMip = 0,
                  uint32_t mipCount = VK_REMAINING_MIP_LEVELS);
void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess);

}  // namespace sample_engine::detail
