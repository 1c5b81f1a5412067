#include "gpu_memory.h"

#include <algorithm>

#include "vk_check.h"

namespace sample_engine::detail {

void Gpu::init(VkPhysicalDevice pd, VkDevice device, VkQueue queue, uint32_t family) {
  physical_ = pd;
  device_ = device;
  queue_ = queue;
  vkGetPhysicalDeviceMemoryProperties(pd, &memProps_);
  VkCommandPoolCreateInfo ci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  ci.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
  ci.queueFamilyIndex = family;
  vkCreateCommandPool(device, &ci, nullptr, &pool_);
}

void Gpu::shutdown() {
  if (pool_) vkDestroyCommandPool(device_, pool_, nullptr);
  pool_ = VK_NULL_HANDLE;
}

uint32_t Gpu::memoryType(uint32_t bits, VkMemoryPropertyFlags props) const {
  for (uint32_t i = 0; i < memProps_.memoryTypeCount; ++i)
    if ((bits & (1u << i)) && (memProps_.memoryTypes[i].propertyFlags & props) == props) return i;
  return UINT32_MAX;
}

std::string Gpu::createBuffer(VkDeviceSize size, VkBufferUsageFlags usage, VkMemoryPropertyFlags props, Buffer& out) {
  out = {};
  out.size = size;
  VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  ci.size = size ? size : 4;  // zero-sized buffers are invalid
  ci.usage = usage;
  ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  SE_VK_TRY(vkCreateBuffer(device_, &ci, nullptr, &out.buffer));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device_, out.buffer, &req);
  VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.pNext = (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) ? &flags : nullptr;
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = memoryType(req.memoryTypeBits, props);
  if (ai.memoryTypeIndex == UINT32_MAX) return "no memory type for buffer";
  SE_VK_TRY(vkAllocateMemory(device_, &ai, nullptr, &out.memory));
  SE_VK_TRY(vkBindBufferMemory(device_, out.buffer, out.memory, 0));
  if (props & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)
    SE_VK_TRY(vkMapMemory(device_, out.memory, 0, VK_WHOLE_SIZE, 0, &out.mapped));
  if (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) {
    VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
    info.buffer = out.buffer;
    out.address = vkGetBufferDeviceAddress(device_, &info);
  }
  return {};
}

std::string Gpu::createBuffers(std::span<const BufferRequest> requests, std::vector<VkDeviceMemory>& blocks) {
  // Blocks of up to 256 MiB; a larger buffer gets a block of its own.
  constexpr VkDeviceSize kBlockSize = VkDeviceSize(256) << 20;
  struct Placement {
    uint32_t type;
    VkDeviceSize offset;
    size_t block;  // index into `pending`
  };
  struct PendingBlock {
    uint32_t type;
    VkDeviceSize size;
    bool deviceAddress;
  };
  std::vector<Placement> placements(requests.size());
  std::vector<PendingBlock> pending;
  std::vector<size_t> openBlock(memProps_.memoryTypeCount, SIZE_MAX);
  for (size_t i = 0; i < requests.size(); ++i) {
    const BufferRequest& r = requests[i];
    Buffer& out = *r.out;
    out = {};
    out.size = r.size;
    VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    ci.size = r.size ? r.size : 4;
    ci.usage = r.usage;
    ci.sharingMode = r.queueFamilies.size() > 1 ? VK_SHARING_MODE_CONCURRENT : VK_SHARING_MODE_EXCLUSIVE;
    ci.queueFamilyIndexCount = r.queueFamilies.size() > 1 ? uint32_t(r.queueFamilies.size()) : 0;
    ci.pQueueFamilyIndices = r.queueFamilies.size() > 1 ? r.queueFamilies.data() : nullptr;
    SE_VK_TRY(vkCreateBuffer(device_, &ci, nullptr, &out.buffer));
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device_, out.buffer, &req);
    const uint32_t type = memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (type == UINT32_MAX) return "no device-local memory type for a buffer";
    size_t b = openBlock[type];
    VkDeviceSize offset = 0;
    if (b != SIZE_MAX) {
      offset = (pending[b].size + req.alignment - 1) / req.alignment * req.alignment;
      if (offset + req.size > kBlockSize) b = SIZE_MAX;
    }
    if (b == SIZE_MAX) {
      b = pending.size();
      pending.push_back({type, 0, false});
      openBlock[type] = b;
      offset = 0;
    }
    pending[b].size = offset + req.size;
    pending[b].deviceAddress |= (r.usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) != 0;
    placements[i] = {type, offset, b};
  }
  const size_t firstBlock = blocks.size();
  for (const PendingBlock& p : pending) {
    VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
    flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.pNext = p.deviceAddress ? &flags : nullptr;
    ai.allocationSize = p.size;
    ai.memoryTypeIndex = p.type;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    SE_VK_TRY(vkAllocateMemory(device_, &ai, nullptr, &memory));
    blocks.push_back(memory);
  }
  for (size_t i = 0; i < requests.size(); ++i) {
    Buffer& out = *requests[i].out;
    SE_VK_TRY(vkBindBufferMemory(device_, out.buffer, blocks[firstBlock + placements[i].block], placements[i].offset));
    if (requests[i].usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) {
      VkBufferDeviceAddressInfo info{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
      info.buffer = out.buffer;
      out.address = vkGetBufferDeviceAddress(device_, &info);
    }
  }
  return {};
}

void Gpu::freeBlocks(std::vector<VkDeviceMemory>& blocks) {
  for (VkDeviceMemory m : blocks) vkFreeMemory(device_, m, nullptr);
  blocks.clear();
}

std::string Gpu::createImage(const ImageDesc& desc, Image& out) {
  out = {};
  out.format = desc.format;
  out.extent = desc.extent;
  out.mipLevels = desc.mipLevels;
  out.layers = desc.cube ? 6 : std::max(desc.arrayLayers, 1u);
  VkImageCreateInfo ci{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ci.flags = (desc.altViewFormat != VK_FORMAT_UNDEFINED ? VK_IMAGE_CREATE_MUTABLE_FORMAT_BIT : 0) |
             (desc.cube ? VK_IMAGE_CREATE_CUBE_COMPATIBLE_BIT : 0);
  ci.imageType = VK_IMAGE_TYPE_2D;
  ci.format = desc.format;
  ci.extent = {desc.extent.width, desc.extent.height, 1};
  ci.mipLevels = desc.mipLevels;
  ci.arrayLayers = out.layers;
  ci.samples = VK_SAMPLE_COUNT_1_BIT;
  ci.tiling = VK_IMAGE_TILING_OPTIMAL;
  ci.usage = desc.usage;
  ci.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  SE_VK_TRY(vkCreateImage(device_, &ci, nullptr, &out.image));
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(device_, out.image, &req);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  if (ai.memoryTypeIndex == UINT32_MAX) ai.memoryTypeIndex = memoryType(req.memoryTypeBits, 0);
  SE_VK_TRY(vkAllocateMemory(device_, &ai, nullptr, &out.memory));
  SE_VK_TRY(vkBindImageMemory(device_, out.image, out.memory, 0));
  VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vi.image = out.image;
  vi.viewType = desc.cube              ? VK_IMAGE_VIEW_TYPE_CUBE
                : desc.arrayLayers > 0 ? VK_IMAGE_VIEW_TYPE_2D_ARRAY
                                       : VK_IMAGE_VIEW_TYPE_2D;
  vi.format = desc.format;
  vi.subresourceRange = {desc.aspect, 0, desc.mipLevels, 0, out.layers};
  SE_VK_TRY(vkCreateImageView(device_, &vi, nullptr, &out.view));
  if (desc.altViewFormat != VK_FORMAT_UNDEFINED) {
    vi.format = desc.altViewFormat;
    SE_VK_TRY(vkCreateImageView(device_, &vi, nullptr, &out.altView));
  }
  return {};
}

void Gpu::destroy(Buffer& b) {
  if (b.buffer) vkDestroyBuffer(device_, b.buffer, nullptr);
  if (b.memory) vkFreeMemory(device_, b.memory, nullptr);  // also unmaps
  b = {};
}

void Gpu::destroy(Image& i) {
  if (i.altView) vkDestroyImageView(device_, i.altView, nullptr);
  if (i.view) vkDestroyImageView(device_, i.view, nullptr);
  if (i.image) vkDestroyImage(device_, i.image, nullptr);
  if (i.memory) vkFreeMemory(device_, i.memory, nullptr);
  i = {};
}

std::string Gpu::beginOneShot(VkCommandBuffer& cmd) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = pool_;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  SE_VK_TRY(vkAllocateCommandBuffers(device_, &ai, &cmd));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  SE_VK_TRY(vkBeginCommandBuffer(cmd, &bi));
  return {};
}

std::string Gpu::endOneShot(VkCommandBuffer cmd) {
  auto cleanup = [&] { vkFreeCommandBuffers(device_, pool_, 1, &cmd); };
  VkResult r = vkEndCommandBuffer(cmd);
  if (r == VK_SUCCESS) {
    VkCommandBufferSubmitInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
    cbi.commandBuffer = cmd;
    VkSubmitInfo2 si{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
    si.commandBufferInfoCount = 1;
    si.pCommandBufferInfos = &cbi;
    r = vkQueueSubmit2(queue_, 1, &si, VK_NULL_HANDLE);
    if (r == VK_SUCCESS) r = vkQueueWaitIdle(queue_);
  }
  cleanup();
  return r == VK_SUCCESS ? std::string() : vkFailure("one-shot submission", r);
}

void imageBarrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout oldLayout,
                  VkImageLayout newLayout, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                  VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess, uint32_t baseMip, uint32_t mipCount) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = srcStage;
  b.srcAccessMask = srcAccess;
  b.dstStageMask = dstStage;
  b.dstAccessMask = dstAccess;
  b.oldLayout = oldLayout;
  b.newLayout = newLayout;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {aspect, baseMip, mipCount, 0, VK_REMAINING_ARRAY_LAYERS};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess) {
  VkMemoryBarrier2 b{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
  b.srcStageMask = srcStage;
  b.srcAccessMask = srcAccess;
  b.dstStageMask = dstStage;
  b.dstAccessMask = dstAccess;
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.memoryBarrierCount = 1;
  dep.pMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

}  // namespace sample_engine::detail
