// The engine's own screen-space effect passes, run after the pre-pass: SSAO (GTAO + blur, compute) and the
// shadow-map visibility output (a fullscreen triangle). Both read the pre-pass images.
#include <algorithm>
#include <cmath>

#include "engine_impl.h"
#include "render_utils.h"

namespace sample_engine {

using namespace detail;

namespace {

constexpr VkImageLayout kReadLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
constexpr VkImageLayout kDepthReadLayout = VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL;

std::string ensureImage(Gpu& gpu, VkExtent2D extent, VkImageUsageFlags writeUsage, Image& image) {
  if (image.image) return {};
  return gpu.createImage(
      {kEffectFormat, extent, writeUsage | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT}, image);
}

// Earlier frames read the image (lighting, readback copies): discard and make it a render target.
void beginWrite(VkCommandBuffer cmd, const Image& image) {
  imageBarrier(cmd, image.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
               VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
               VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
}

void endWrite(VkCommandBuffer cmd, const Image& image) {
  imageBarrier(cmd, image.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, kReadLayout,
               VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
               VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
}

// The compute counterparts: discard and make it a storage image; then readable by the blur (compute) and the
// lighting (fragment).
void beginComputeWrite(VkCommandBuffer cmd, const Image& image) {
  imageBarrier(cmd, image.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL,
               VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
               VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
}

void endComputeWrite(VkCommandBuffer cmd, const Image& image) {
  imageBarrier(cmd, image.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_GENERAL, kReadLayout,
               VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
               VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
               VK_ACCESS_2_SHADER_SAMPLED_READ_BIT);
}

// SsaoSettings::kernelSize -> slices and taps per side (the split documented there).
SsaoConstants ssaoConstants(const SsaoSettings& settings) {
  const uint32_t taps = std::clamp(settings.kernelSize, 1u, kMaxSsaoKernelSize);
  const uint32_t slices = std::max(1u, uint32_t(std::sqrt(float(taps / 2))));
  return {std::max(settings.radius, 1e-4f), std::max(settings.bias, 0.0f), std::max(settings.power, 0.0f), slices,
          std::max(1u, taps / (2 * slices))};
}

constexpr uint32_t kSsaoGroupSize = 8;  // local_size of shaders/ssao_inputs.glsl

void dispatchSsao(VkCommandBuffer cmd, const Pipelines& p, VkPipeline pipeline, VkDescriptorSet frameSet,
                  VkDescriptorSet inputSet, const SsaoConstants& constants, VkExtent2D extent) {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline);
  VkDescriptorSet sets[2] = {frameSet, inputSet};
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.ssaoLayout, 0, 2, sets, 0, nullptr);
  vkCmdPushConstants(cmd, p.ssaoLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(constants), &constants);
  vkCmdDispatch(cmd, (extent.width + kSsaoGroupSize - 1) / kSsaoGroupSize,
                (extent.height + kSsaoGroupSize - 1) / kSsaoGroupSize, 1);
}

void writeSsaoOutput(VkDevice device, VkDescriptorSet set, VkImageView view) {
  const VkDescriptorImageInfo info{VK_NULL_HANDLE, view, VK_IMAGE_LAYOUT_GENERAL};
  VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  w.dstSet = set;
  w.dstBinding = kSsaoOutputBinding;
  w.descriptorCount = 1;
  w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
  w.pImageInfo = &info;
  vkUpdateDescriptorSets(device, 1, &w, 0, nullptr);
}

}  // namespace

std::string Engine::Impl::ensureEffectImages(const FrameParams& params) {
  std::string e;
  if (params.ssao.enabled) {
    e = ensureImage(gpu, targets.extent, VK_IMAGE_USAGE_STORAGE_BIT, targets.ssao);
    if (e.empty() && params.ssao.blur)
      e = ensureImage(gpu, targets.extent, VK_IMAGE_USAGE_STORAGE_BIT, targets.ssaoRaw);
  }
  if (e.empty() && params.outputShadowVisibility)
    e = ensureImage(gpu, targets.extent, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, targets.shadowVisibility);
  return e;
}

void Engine::Impl::recordSsao(FrameResources& frame, const SsaoSettings& settings) {
  VkCommandBuffer cmd = frame.cmd;
  const SsaoConstants constants = ssaoConstants(settings);
  const VkDescriptorImageInfo depth{pipelines.nearestSampler, targets.depth.view, kDepthReadLayout};
  const VkDescriptorImageInfo normal{pipelines.nearestSampler, targets.geometricNormal.view, kReadLayout};
  const VkDescriptorImageInfo unused{pipelines.nearestSampler, defaults.white.view, kReadLayout};
  const Image& raw = settings.blur ? targets.ssaoRaw : targets.ssao;

  writeImageDescriptors(ctx.device, frame.ssaoSet, {depth, normal, unused});
  writeSsaoOutput(ctx.device, frame.ssaoSet, raw.view);
  beginComputeWrite(cmd, raw);
  dispatchSsao(cmd, pipelines, pipelines.ssao, frame.frameSet, frame.ssaoSet, constants, targets.extent);
  endComputeWrite(cmd, raw);
  if (!settings.blur) return;

  writeImageDescriptors(ctx.device, frame.ssaoBlurSet,
                        {depth, normal, {pipelines.nearestSampler, raw.view, kReadLayout}});
  writeSsaoOutput(ctx.device, frame.ssaoBlurSet, targets.ssao.view);
  beginComputeWrite(cmd, targets.ssao);
  dispatchSsao(cmd, pipelines, pipelines.ssaoBlur, frame.frameSet, frame.ssaoBlurSet, constants, targets.extent);
  endComputeWrite(cmd, targets.ssao);
}

void Engine::Impl::recordShadowVisibility(FrameResources& frame) {
  VkCommandBuffer cmd = frame.cmd;
  writeImageDescriptors(ctx.device, frame.shadowVisibilitySet,
                        {{pipelines.nearestSampler, targets.depth.view, kDepthReadLayout},
                         {pipelines.nearestSampler, targets.normalRoughness.view, kReadLayout},
                         {pipelines.nearestSampler, targets.geometricNormal.view, kReadLayout},
                         {pipelines.shadowSampler, targets.shadowMap.view, kReadLayout}});
  beginWrite(cmd, targets.shadowVisibility);
  drawFullscreen(cmd, pipelines, pipelines.shadowVisibility, frame.frameSet, frame.shadowVisibilitySet,
                 targets.shadowVisibility.view, targets.extent);
  endWrite(cmd, targets.shadowVisibility);
}

}  // namespace sample_engine
