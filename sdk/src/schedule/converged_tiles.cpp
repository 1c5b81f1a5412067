#include "converged_tiles.h"

#include <cmath>
#include <string>

#include "context_impl.h"
#include "denoise_rgb_interface.glsl"
#include "denoiser_history.h"
#include "memory_barrier.h"
#include "pass_core.h"
#include "raybridge_shaders.h"
#include "tile_classifier.h"

namespace rb {

Status ConvergedTiles::init(Context& ctx, const char* who) {
  const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
  auto binding = [&](uint32_t b, VkDescriptorType t) { return VkDescriptorSetLayoutBinding{b, t, 1, cs, nullptr}; };
  const VkDescriptorType sampled = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  std::vector<VkDescriptorSetLayoutBinding> common = {binding(RB_CONVERGED_BINDING_DEPTH, sampled),
                                                      binding(RB_CONVERGED_BINDING_MOTION, sampled),
                                                      binding(RB_CONVERGED_BINDING_HISTORY, sampled),
                                                      binding(RB_CONVERGED_BINDING_DISTANCE, sampled),
                                                      binding(RB_CONVERGED_BINDING_STATE,
                                                              VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                                                      binding(RB_CONVERGED_BINDING_REACTIVE, sampled)};
  const bool rgb = signal_ != DenoiseSignal::Scalar;
  if (rgb) common.push_back(binding(RB_CONVERGED_BINDING_ROUGHNESS, sampled));
  if (!mark_.pipeline) {
    std::vector<VkDescriptorSetLayoutBinding> b = common;
    if (!rgb) b.push_back(binding(RB_CONVERGED_BINDING_NOISE, sampled));
    if (rgb) b.push_back(binding(RB_CONVERGED_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER));
    b.push_back(binding(RB_CONVERGED_BINDING_VISIBILITY, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE));
    const SpirvModule shader = rgb ? SpirvModule::of(spirv::rgb_converged_comp)
                                   : SpirvModule::of(spirv::shadow_converged_comp);
    Result<ComputePipeline> p = ComputePipeline::create(ctx, shader, b, sizeof(ConvergedTileConstants),
                                                        (std::string(who) + ": converged tiles").c_str());
    if (!p) return p.error();
    mark_ = p.value();
  }
  if (!check_.pipeline) {
    std::vector<VkDescriptorSetLayoutBinding> b = common;
    // RGB signals: the output in GENERAL, read and marked where a tile is held (before the pass's endWrite()).
    b.push_back(binding(RB_CONVERGED_BINDING_VISIBILITY, rgb ? VK_DESCRIPTOR_TYPE_STORAGE_IMAGE : sampled));
    const SpirvModule shader = rgb ? SpirvModule::of(spirv::rgb_converged_check_comp)
                                   : SpirvModule::of(spirv::shadow_converged_check_comp);
    Result<ComputePipeline> p = ComputePipeline::create(ctx, shader, b, sizeof(ConvergedTileConstants),
                                                        (std::string(who) + ": converged tiles, check").c_str());
    if (!p) return p.error();
    check_ = p.value();
  }
  return {};
}

void ConvergedTiles::retire(Context& ctx) {
  mark_.retire(ctx);
  check_.retire(ctx);
}

Result<bool> ConvergedTiles::record(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g,
                                    const ConvergedTileSettings& s, const Denoiser* denoiser, uint32_t raysPerPixel,
                                    TileClassifier& classifier, VkImageView visibility, const char* who,
                                    float roughnessThreshold, VkDescriptorBufferInfo counters) {
  const DenoiseHistory history = internal::historyFor(*denoiser, g);
  if (!history.mean || !history.valid) return false;
  ConvergedTileConstants pc{};
  if (Status st = internal::historyReprojection(history, g, ctx.frameIndex(), who, pc.denoise); !st) {
    return st.error();
  }
  if (Status st = init(ctx, who); !st) return st.error();
  pc.denoise.signalRaysPerPixel = float(raysPerPixel);
  if (signal_ == DenoiseSignal::Reflection) {
    pc.denoise.roughnessThreshold = roughnessThreshold;
    pc.denoise.flags |= RB_DN_RGB_REFLECTION | (roughnessInImage(g) ? RB_DN_RGB_ROUGHNESS_IMAGE : 0u);
  }
  pc.minFrames = s.minFrames ? s.minFrames : kDefaultConvergedMinFrames;
  pc.maxNoise = s.maxNoise > 0.0f ? s.maxNoise : kDefaultConvergedMaxNoise;
  pc.refreshPeriod = s.refreshPeriod ? s.refreshPeriod : kDefaultConvergedRefreshPeriod;
  // The pass's own count of recordings, not the context's frame index: every tile refreshes once in refreshPeriod
  // recordings however the engine's frame index steps.
  pc.frameIndex = recordings_++;
  constants_ = pc;

  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  const VkPipelineStageFlags cs = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  const VkAccessFlags rw = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  if (classifier.takeStateReset()) {
    // A new state buffer: no tile held. (The previous frame's users of the old one are a different buffer.)
    vk.vkCmdFillBuffer(cmd, classifier.stateBuffer(), 0, VK_WHOLE_SIZE, 0);
    recordMemoryBarrier(vk, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, cs, rw);
  } else {
    // Last frame's check and classifier are done with the state.
    recordMemoryBarrier(vk, cmd, cs, rw, cs, rw);
  }
  history_ = history;
  DescriptorWrites w;
  writeCommon(w, g, classifier);
  if (signal_ == DenoiseSignal::Scalar) {
    w.sampledImage(RB_CONVERGED_BINDING_NOISE, history.noise, history.sampler,
                   VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  } else {
    w.storageBuffer(RB_CONVERGED_BINDING_COUNTERS, counters.buffer, counters.offset, counters.range);
  }
  w.storageImage(RB_CONVERGED_BINDING_VISIBILITY, visibility);
  mark_.dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height);
  // The state and the marks, for the classifier (which may overwrite a tile that needs no ray with its exact values),
  // or for an RGB signal the ray generation shader (which reads the state and writes the traced tiles).
  recordMemoryBarrier(vk, cmd, cs, VK_ACCESS_SHADER_WRITE_BIT,
                      signal_ != DenoiseSignal::Scalar ? cs | VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR : cs, rw);
  // The pass's output now holds kept-history marks: the denoiser that filters it this frame reads them as such.
  internal::contextImpl(ctx).markKeptHistory(visibility);
  return true;
}

void ConvergedTiles::writeCommon(DescriptorWrites& w, const GBufferDesc& g, const TileClassifier& classifier) const {
  const VkImageLayout ro = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  w.sampledImage(RB_CONVERGED_BINDING_DEPTH, g.depth.view, history_.sampler, readLayout(g.depth));
  internal::writeReprojectionInputs(w, g, history_.sampler, RB_CONVERGED_BINDING_MOTION, RB_CONVERGED_BINDING_REACTIVE);
  w.sampledImage(RB_CONVERGED_BINDING_HISTORY, history_.mean, history_.sampler, ro);
  w.sampledImage(RB_CONVERGED_BINDING_DISTANCE, history_.distance, history_.sampler, ro);
  classifier.writeState(w, RB_CONVERGED_BINDING_STATE);
  if (signal_ != DenoiseSignal::Scalar) {
    // The roughness image, else the normal image (roughness in .w): as the RGB denoiser reads it (reflections; for
    // local lights a valid image the shaders do not read).
    const GBufferImage& roughness = roughnessImage(g);
    w.sampledImage(RB_CONVERGED_BINDING_ROUGHNESS, roughness.view, history_.sampler, readLayout(roughness));
  }
}

void ConvergedTiles::check(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, const TileClassifier& classifier,
                           VkImageView visibility) const {
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  // The state: written by step 1 and read by the classifier, both compute.
  recordMemoryBarrier(vk, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                      VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                      VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  DescriptorWrites w;
  writeCommon(w, g, classifier);
  if (signal_ != DenoiseSignal::Scalar) {
    // The trace's output, still in GENERAL: read and written here.
    recordMemoryBarrier(vk, cmd, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, VK_ACCESS_SHADER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    w.storageImage(RB_CONVERGED_BINDING_VISIBILITY, visibility);
  } else {
    w.sampledImage(RB_CONVERGED_BINDING_VISIBILITY, visibility, history_.sampler,
                   VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  }
  check_.dispatch(ctx, cmd, w.writes, &constants_, sizeof constants_, g.width, g.height);
}

Result<bool> ConvergedTiles::traceSkipping(PassCore& core, Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g,
                                           const ConvergedTileSettings& settings, const Denoiser* history,
                                           uint32_t raysPerPixel, TileClassifier& state, DescriptorWrites& w,
                                           const void* constants, uint32_t constantBytes,
                                           const RayTracingPipeline& skipping, uint32_t stateBinding, const char* who,
                                           float roughnessThreshold) {
  const VkDescriptorBufferInfo counters{core.metrics.counterBuffer(), core.metrics.counterOffset(ctx),
                                        core.metrics.counterBytes()};
  Result<bool> marked = record(ctx, cmd, g, settings, history, raysPerPixel, state, core.images[0].view, who,
                               roughnessThreshold, counters);
  if (!marked) {
    core.end(ctx, cmd);
    return marked.error();
  }
  if (!marked.value()) return false;
  // Every pixel, the converged tiles' returning at once (their outputs are written); then the check, which marks
  // held tiles in the output before it is made readable, inside the pass's time.
  state.writeState(w, stateBinding);
  core.bind(ctx, cmd, w, constants, constantBytes, &skipping);
  skipping.trace(ctx, cmd, g.width, g.height);
  check(ctx, cmd, g, state, core.images[0].view);
  core.images.endWrite(ctx, cmd);
  core.metrics.writeEnd(ctx, cmd);
  return true;
}

}  // namespace rb
