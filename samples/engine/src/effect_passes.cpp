// The engine's own screen-space effect passes, run after the pre-pass: SSAO (+ blur) and the shadow-map
// visibility output. Both are fullscreen triangles over the pre-pass images.
#include <algorithm>

#include "engine_impl.h"
#include "render_utils.h"

namespace sample_engine {

using namespace detail;

namespace {

constexpr VkImageLayout kReadLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
constexpr VkImageLayout kDepthReadLayout = VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL;

std::string ensureImage(Gpu& gpu, VkExtent2D extent, Image& image) {
  if (image.image) return {};
  return gpu.createImage({kEffectFormat, extent,
                          VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
                              VK_IMAGE_USAGE_TRANSFER_SRC_BIT},
                         image);
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

}  // namespace

std::string Engine::Impl::ensureEffectImages(const FrameParams& params) {
  std::string e;
  if (params.ssao.enabled) {
    e = ensureImage(gpu, targets.extent, targets.ssao);
    if (e.empty() && params.ssao.blur) e = ensureImage(gpu, targets.extent, targets.ssaoRaw);
  }
  if (e.empty() && params.outputShadowVisibility) e = ensureImage(gpu, targets.extent, targets.shadowVisibility);
  return e;
}

void Engine::Impl::recordSsao(FrameResources& frame, const SsaoSettings& settings) {
  VkCommandBuffer cmd = frame.cmd;
  const SsaoConstants constants{std::max(settings.radius, 1e-4f), std::max(settings.bias, 0.0f),
                                std::max(settings.power, 0.0f), std::clamp(settings.kernelSize, 1u, 64u)};
  const VkDescriptorImageInfo depth{pipelines.nearestSampler, targets.depth.view, kDepthReadLayout};
  const VkDescriptorImageInfo normal{pipelines.nearestSampler, targets.geometricNormal.view, kReadLayout};
  const VkDescriptorImageInfo unused{pipelines.nearestSampler, defaults.white.view, kReadLayout};
  const Image& raw = settings.blur ? targets.ssaoRaw : targets.ssao;

  writeImageDescriptors(ctx.device, frame.ssaoSet, {depth, normal, unused, unused});
  beginWrite(cmd, raw);
  drawFullscreen(cmd, pipelines, pipelines.ssao, frame.frameSet, frame.ssaoSet, constants, raw.view, targets.extent);
  endWrite(cmd, raw);
  if (!settings.blur) return;

  writeImageDescriptors(ctx.device, frame.ssaoBlurSet,
                        {depth, normal, {pipelines.nearestSampler, raw.view, kReadLayout}, unused});
  beginWrite(cmd, targets.ssao);
  drawFullscreen(cmd, pipelines, pipelines.ssaoBlur, frame.frameSet, frame.ssaoBlurSet, constants, targets.ssao.view,
                 targets.extent);
  endWrite(cmd, targets.ssao);
}

void Engine::Impl::recordShadowVisibility(FrameResources& frame) {
  VkCommandBuffer cmd = frame.cmd;
  writeImageDescriptors(ctx.device, frame.shadowVisibilitySet,
                        {{pipelines.nearestSampler, targets.depth.view, kDepthReadLayout},
                         {pipelines.nearestSampler, targets.normalRoughness.view, kReadLayout},
                         {pipelines.nearestSampler, targets.geometricNormal.view, kReadLayout},
                         {pipelines.shadowSampler, targets.shadowMap.view, kReadLayout}});
  beginWrite(cmd, targets.shadowVisibility);
  drawFullscreen(cmd, pipelines, pipelines.shadowVisibility, frame.frameSet, frame.shadowVisibilitySet, {},
                 targets.shadowVisibility.view, targets.extent);
  endWrite(cmd, targets.shadowVisibility);
}

}  // namespace sample_engine
