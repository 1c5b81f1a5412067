#include "neutral_images.h"

#include "context_impl.h"
#include "image_barriers.h"

namespace rb {

namespace {
// Cleared by a transfer; readable by copies too, like every output (an engine may capture them).
constexpr VkImageUsageFlags kNeutralUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
}  // namespace

Status NeutralImages::ensure(Context& ctx) {
  if (exist()) return {};
  Result<GpuImage> white = createStorageImage(ctx, 1, 1, VK_FORMAT_R16_SFLOAT, kNeutralUsage,
                                              MemoryCategory::PassImages, "neutral visibility (effect off)");
  if (!white) return white.error();
  Result<GpuImage> black = createStorageImage(ctx, 1, 1, VK_FORMAT_R16G16B16A16_SFLOAT, kNeutralUsage,
                                              MemoryCategory::PassImages, "neutral radiance (effect off)");
  if (!black) {
    GpuImage w = white.value();
    retireImage(ctx, w);
    return black.error();
  }
  white_ = white.value();
  black_ = black.value();
  initialised_ = false;
  return {};
}

void NeutralImages::recordInit(Context& ctx, VkCommandBuffer cmd) {
  if (!exist() || initialised_) return;
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  VkImageMemoryBarrier toClear[2] = {
      colorImageBarrier(white_.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 0,
                        VK_ACCESS_TRANSFER_WRITE_BIT),
      colorImageBarrier(black_.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 0,
                        VK_ACCESS_TRANSFER_WRITE_BIT)};
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0,
                          nullptr, 2, toClear);
  const VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  VkClearColorValue one{};
  one.float32[0] = 1.0f;
  const VkClearColorValue zero{};
  vk.vkCmdClearColorImage(cmd, white_.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &one, 1, &range);
  vk.vkCmdClearColorImage(cmd, black_.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &zero, 1, &range);
  VkImageMemoryBarrier toRead[2] = {
      colorImageBarrier(white_.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                        VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT),
      colorImageBarrier(black_.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                        VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT)};
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                          VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                              VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
                          0, 0, nullptr, 0, nullptr, 2, toRead);
  initialised_ = true;
}

void NeutralImages::retire(Context& ctx) {
  if (white_.image) retireImage(ctx, white_);
  if (black_.image) retireImage(ctx, black_);
  white_ = {};
  black_ = {};
  initialised_ = false;
}

}  // namespace rb
