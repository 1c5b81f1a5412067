#include "gpu_memory.h"

#include <string>

#include "context_impl.h"

namespace rb {

namespace {

void account(MemoryStats& m, MemoryCategory category, VkDeviceSize bytes, bool add) {
  VkDeviceSize& slot = m.bytes[static_cast<size_t>(category)];
  if (add) {
    slot += bytes;
    ++m.allocations;
  } else {
    slot -= bytes;
    --m.allocations;
  }
}

// The Context's totals and, when it has one, the owner's (Context::Impl::ownerMemory).
void account(Context::Impl& c, MemoryCategory category, uint32_t owner, VkDeviceSize bytes, bool add) {
  account(c.memory, category, bytes, add);
  if (owner != 0 && owner <= c.ownerMemory.size()) account(c.ownerMemory[owner - 1], category, bytes, add);
}

Result<VkDeviceMemory> allocate(Context::Impl& c, const VkMemoryRequirements& req, MemoryLocation location,
                                bool deviceAddress, const char* what) {
  const VkMemoryPropertyFlags host = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  const VkMemoryPropertyFlags deviceLocal = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  const VkMemoryPropertyFlags required = location == MemoryLocation::DeviceLocal ? deviceLocal : host;
  const VkMemoryPropertyFlags preferred = location == MemoryLocation::HostVisibleDeviceLocal ? host | deviceLocal
                                                                                             : required;
  int32_t type = c.findMemoryType(req.memoryTypeBits, required, preferred);
  if (type < 0 && location == MemoryLocation::DeviceLocal) type = c.findMemoryType(req.memoryTypeBits, 0, 0);
  if (type < 0) {
    return Error{ErrorCode::VulkanError, VK_ERROR_OUT_OF_DEVICE_MEMORY, std::string("no memory type fits ") + what};
  }
  VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
  flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
  VkMemoryAllocateInfo info{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, deviceAddress ? &flags : nullptr};
  info.allocationSize = req.size;
  info.memoryTypeIndex = static_cast<uint32_t>(type);
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkResult r = c.vk.vkAllocateMemory(c.desc.device, &info, c.allocator(), &memory);
  if (r != VK_SUCCESS) {
    return vulkanError(r, std::string("vkAllocateMemory(") + std::to_string(req.size) + " bytes for " + what + ")");
  }
  return memory;
}

}  // namespace

Result<GpuBuffer> createBuffer(Context& ctx, VkDeviceSize size, VkBufferUsageFlags usage, MemoryLocation location,
                               MemoryCategory category, const char* what, std::span<const uint32_t> sharedWith) {
  Context::Impl& c = internal::contextImpl(ctx);
  GpuBuffer out;
  out.size = size;
  out.category = category;
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = size;
  info.usage = usage;
  info.sharingMode = sharedWith.size() >= 2 ? VK_SHARING_MODE_CONCURRENT : VK_SHARING_MODE_EXCLUSIVE;
  if (sharedWith.size() >= 2) {
    info.queueFamilyIndexCount = static_cast<uint32_t>(sharedWith.size());
    info.pQueueFamilyIndices = sharedWith.data();
  }
  VkResult r = c.vk.vkCreateBuffer(c.desc.device, &info, c.allocator(), &out.buffer);
  if (r != VK_SUCCESS) return vulkanError(r, std::string("vkCreateBuffer for ") + what);
  VkMemoryRequirements req;
  c.vk.vkGetBufferMemoryRequirements(c.desc.device, out.buffer, &req);
  bool deviceAddress = (usage & VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT) != 0;
  Result<VkDeviceMemory> memory = allocate(c, req, location, deviceAddress, what);
  if (!memory) {
    c.vk.vkDestroyBuffer(c.desc.device, out.buffer, c.allocator());
    return memory.error();
  }
  out.memory = memory.value();
  out.allocatedBytes = req.size;
  r = c.vk.vkBindBufferMemory(c.desc.device, out.buffer, out.memory, 0);
  const char* failed = r != VK_SUCCESS ? "vkBindBufferMemory" : nullptr;
  if (!failed && location != MemoryLocation::DeviceLocal) {
    r = c.vk.vkMapMemory(c.desc.device, out.memory, 0, VK_WHOLE_SIZE, 0, &out.mapped);
    if (r != VK_SUCCESS) failed = "vkMapMemory";
  }
  if (failed) {
    c.vk.vkDestroyBuffer(c.desc.device, out.buffer, c.allocator());
    c.vk.vkFreeMemory(c.desc.device, out.memory, c.allocator());
    return vulkanError(r, std::string(failed) + " for " + what);
  }
  if (deviceAddress) {
    VkBufferDeviceAddressInfo addr{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
    addr.buffer = out.buffer;
    out.address = c.vk.vkGetBufferDeviceAddress(c.desc.device, &addr);
  }
  out.owner = c.memoryOwner;
  account(c, category, out.owner, out.allocatedBytes, true);
  return out;
}

void destroyBuffer(Context& ctx, GpuBuffer& buffer) {
  if (!buffer.valid()) return;
  Context::Impl& c = internal::contextImpl(ctx);
  c.vk.vkDestroyBuffer(c.desc.device, buffer.buffer, c.allocator());
  c.vk.vkFreeMemory(c.desc.device, buffer.memory, c.allocator());
  account(c, buffer.category, buffer.owner, buffer.allocatedBytes, false);
  buffer = GpuBuffer{};
}

void retireBuffer(Context& ctx, GpuBuffer& buffer) {
  if (!buffer.valid()) return;
  GpuBuffer copy = buffer;
  buffer = GpuBuffer{};
  Context* context = &ctx;
  internal::contextImpl(ctx).retire([context, copy]() mutable { destroyBuffer(*context, copy); });
}

Result<GpuImage> createStorageImage(Context& ctx, uint32_t width, uint32_t height, VkFormat format,
                                    VkImageUsageFlags extraUsage, MemoryCategory category, const char* what) {
  Context::Impl& c = internal::contextImpl(ctx);
  GpuImage out;
  out.format = format;
  out.width = width;
  out.height = height;
  out.category = category;
  VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  info.imageType = VK_IMAGE_TYPE_2D;
  info.format = format;
  info.extent = {width, height, 1};
  info.mipLevels = 1;
  info.arrayLayers = 1;
  info.samples = VK_SAMPLE_COUNT_1_BIT;
  info.tiling = VK_IMAGE_TILING_OPTIMAL;
  info.usage = VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | extraUsage;
  info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkResult r = c.vk.vkCreateImage(c.desc.device, &info, c.allocator(), &out.image);
  if (r != VK_SUCCESS) return vulkanError(r, std::string("vkCreateImage for ") + what);
  VkMemoryRequirements req;
  c.vk.vkGetImageMemoryRequirements(c.desc.device, out.image, &req);
  Result<VkDeviceMemory> memory = allocate(c, req, MemoryLocation::DeviceLocal, false, what);
  if (!memory) {
    c.vk.vkDestroyImage(c.desc.device, out.image, c.allocator());
    return memory.error();
  }
  out.memory = memory.value();
  out.allocatedBytes = req.size;
  r = c.vk.vkBindImageMemory(c.desc.device, out.image, out.memory, 0);
  if (r != VK_SUCCESS) {
    c.vk.vkDestroyImage(c.desc.device, out.image, c.allocator());
    c.vk.vkFreeMemory(c.desc.device, out.memory, c.allocator());
    return vulkanError(r, std::string("vkBindImageMemory for ") + what);
  }
  VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  view.image = out.image;
  view.viewType = VK_IMAGE_VIEW_TYPE_2D;
  view.format = format;
  view.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  r = c.vk.vkCreateImageView(c.desc.device, &view, c.allocator(), &out.view);
  if (r != VK_SUCCESS) {
    c.vk.vkDestroyImage(c.desc.device, out.image, c.allocator());
    c.vk.vkFreeMemory(c.desc.device, out.memory, c.allocator());
    return vulkanError(r, std::string("vkCreateImageView for ") + what);
  }
  out.owner = c.memoryOwner;
  account(c, category, out.owner, out.allocatedBytes, true);
  return out;
}

void destroyImage(Context& ctx, GpuImage& image) {
  if (!image.valid()) return;
  Context::Impl& c = internal::contextImpl(ctx);
  c.vk.vkDestroyImageView(c.desc.device, image.view, c.allocator());
  c.vk.vkDestroyImage(c.desc.device, image.image, c.allocator());
  c.vk.vkFreeMemory(c.desc.device, image.memory, c.allocator());
  account(c, image.category, image.owner, image.allocatedBytes, false);
  image = GpuImage{};
}

void retireImage(Context& ctx, GpuImage& image) {
  if (!image.valid()) return;
  GpuImage copy = image;
  image = GpuImage{};
  Context* context = &ctx;
  internal::contextImpl(ctx).retire([context, copy]() mutable { destroyImage(*context, copy); });
}

}  // namespace rb
