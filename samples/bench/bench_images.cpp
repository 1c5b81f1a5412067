#include "bench_images.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "context_impl.h"
#include "foliage_scene.h"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace rbbench {

SampledImage uploadSampledImage(BenchEnv& env, VkFormat format, VkImageAspectFlags aspect, uint32_t width,
                                uint32_t height, const void* data, size_t bytes, const char* what) {
  const rb::DeviceFunctions& vk = env.vk();
  VkDevice device = env.device().device();
  auto fail = [&](VkResult r, const char* call) {
    return BenchFailure(std::string(call) + " for " + what + " failed: " + std::to_string(r));
  };
  SampledImage img;
  VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ici.imageType = VK_IMAGE_TYPE_2D;
  ici.format = format;
  ici.extent = {width, height, 1};
  ici.mipLevels = ici.arrayLayers = 1;
  ici.samples = VK_SAMPLE_COUNT_1_BIT;
  ici.tiling = VK_IMAGE_TILING_OPTIMAL;
  ici.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  if (VkResult r = vk.vkCreateImage(device, &ici, nullptr, &img.image); r != VK_SUCCESS) throw fail(r, "vkCreateImage");
  VkMemoryRequirements req;
  vk.vkGetImageMemoryRequirements(device, img.image, &req);
  const int32_t type = rb::internal::contextImpl(env.ctx()).findMemoryType(req.memoryTypeBits,
                                                                           VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0);
  if (type < 0) throw BenchFailure(std::string("no device-local memory type for ") + what);
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = uint32_t(type);
  if (VkResult r = vk.vkAllocateMemory(device, &mai, nullptr, &img.memory); r != VK_SUCCESS) {
    throw fail(r, "vkAllocateMemory");
  }
  vk.vkBindImageMemory(device, img.image, img.memory, 0);
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = img.image;
  vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vci.format = format;
  vci.subresourceRange = {aspect, 0, 1, 0, 1};
  if (VkResult r = vk.vkCreateImageView(device, &vci, nullptr, &img.view); r != VK_SUCCESS) {
    throw fail(r, "vkCreateImageView");
  }

  rb::HeadlessBuffer staging = check(env.device().createBuffer(bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, data),
                                     std::string("staging ") + what);
  VkCommandBuffer cmd = check(env.device().beginCommands(), std::string("uploading ") + what);
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = img.image;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0,
                          nullptr, 1, &b);
  VkBufferImageCopy region{};
  region.imageSubresource = {aspect, 0, 0, 1};
  region.imageExtent = {width, height, 1};
  vk.vkCmdCopyBufferToImage(cmd, staging.buffer, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
  b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  b.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                          VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0,
                          nullptr, 0, nullptr, 1, &b);
  check(env.device().submitAndWait(cmd), std::string("uploading ") + what);
  env.device().destroyBuffer(staging);
  return img;
}

void destroySampledImage(BenchEnv& env, SampledImage& img) {
  VkDevice device = env.device().device();
  env.vk().vkDestroyImageView(device, img.view, nullptr);
  env.vk().vkDestroyImage(device, img.image, nullptr);
  env.vk().vkFreeMemory(device, img.memory, nullptr);
  img = {};
}

std::vector<uint8_t> readImage(BenchEnv& env, VkImage image, VkImageLayout layout, uint32_t w, uint32_t h,
                               uint32_t texelBytes, const char* what) {
  const rb::DeviceFunctions& vk = env.vk();
  const VkDeviceSize bytes = VkDeviceSize(w) * h * texelBytes;
  rb::HeadlessBuffer staging = check(env.device().createBuffer(bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true),
                                     std::string("creating a readback buffer for ") + what);
  VkCommandBuffer cmd = check(env.device().beginCommands(), std::string("beginning the readback of ") + what);
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  b.oldLayout = layout;
  b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0,
                          nullptr, 1, &b);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {w, h, 1};
  vk.vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, staging.buffer, 1, &region);
  // Back to the layout its owner promised.
  b.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  b.newLayout = layout;
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0, nullptr, 0,
                          nullptr, 1, &b);
  check(env.device().submitAndWait(cmd), std::string("reading back ") + what);
  std::vector<uint8_t> out(bytes);
  std::memcpy(out.data(), staging.mapped, bytes);
  env.device().destroyBuffer(staging);
  return out;
}

std::vector<float> readRgba16f(BenchEnv& env, VkImage image, VkImageLayout layout, uint32_t w, uint32_t h,
                               const char* what) {
  // Every half once: 2560x1440 readbacks come by the hundred in the lights scenario.
  static const std::vector<float> table = [] {
    std::vector<float> t(65536);
    for (uint32_t i = 0; i < t.size(); ++i) t[i] = halfToFloat(uint16_t(i));
    return t;
  }();
  const std::vector<uint8_t> raw = readImage(env, image, layout, w, h, 8, what);
  std::vector<float> out(size_t(w) * h * 4);
  for (size_t i = 0; i < out.size(); ++i) {
    uint16_t half;
    std::memcpy(&half, raw.data() + 2 * i, 2);
    out[i] = table[half];
  }
  return out;
}

void writeTonemappedPng(const std::string& path, const std::vector<float>& rgba, uint32_t w, uint32_t h,
                        double exposure) {
  std::vector<uint8_t> png(size_t(w) * h * 3);
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    for (int c = 0; c < 3; ++c) {
      const double x = std::max(0.0, double(rgba[4 * i + c]) * exposure);
      const double linear = x / (1.0 + x);
      const double srgb = linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
      png[3 * i + c] = uint8_t(std::clamp(srgb * 255.0 + 0.5, 0.0, 255.0));
    }
  }
  if (!stbi_write_png(path.c_str(), int(w), int(h), 3, png.data(), int(w) * 3)) {
    throw BenchFailure("could not write " + path + " (does its folder exist and is it writable?)");
  }
}

}  // namespace rbbench
