#include "pass_images.h"

#include "context_impl.h"
#include "image_barriers.h"

namespace rb {

Status PassImages::ensure(Context& ctx, uint32_t width, uint32_t height, const std::vector<Spec>& specs) {
  bool same = images_.size() == specs.size();
  for (size_t i = 0; same && i < specs.size(); ++i) {
    same = images_[i].width == width && images_[i].height == height && images_[i].format == specs[i].format;
  }
  if (same) return {};
  retire(ctx);
  for (const Spec& s : specs) {
    Result<GpuImage> img = createStorageImage(ctx, width, height, s.format, VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                              MemoryCategory::PassImages, s.name);
    if (!img) return img.error();
    images_.push_back(img.value());
  }
  return {};
}

void PassImages::retire(Context& ctx) {
  for (GpuImage& img : images_) retireImage(ctx, img);
  images_.clear();
}

namespace {
void transition(Context& ctx, VkCommandBuffer cmd, const std::vector<GpuImage>& images, VkImageLayout from,
                VkImageLayout to, VkAccessFlags srcAccess, VkAccessFlags dstAccess, VkPipelineStageFlags srcStage,
                VkPipelineStageFlags dstStage) {
  std::vector<VkImageMemoryBarrier> barriers;
  for (const GpuImage& img : images) barriers.push_back(colorImageBarrier(img.image, from, to, srcAccess, dstAccess));
  if (barriers.empty()) return;
  internal::deviceFunctions(ctx).vkCmdPipelineBarrier(cmd, srcStage, dstStage, 0, 0, nullptr, 0, nullptr,
                                                      static_cast<uint32_t>(barriers.size()), barriers.data());
}
}  // namespace

void PassImages::beginWrite(Context& ctx, VkCommandBuffer cmd) {
  // The previous frame's readers (the engine's lighting, a denoiser) finish before the overwrite.
  transition(ctx, cmd, images_, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_ACCESS_SHADER_READ_BIT,
             VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_SHADER_READ_BIT,
             VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                 VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
             VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
}

void PassImages::endWrite(Context& ctx, VkCommandBuffer cmd) {
  transition(ctx, cmd, images_, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
             VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT,
             VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
             VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                 VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR);
}

}  // namespace rb
