#include "pass_core.h"

#include "context_impl.h"
#include "gbuffer_sampler.h"

namespace rb {

Status PassCore::init(Context& ctx, const RayTracingPipelineDesc& desc) {
  Result<RayTracingPipeline> p = RayTracingPipeline::create(ctx, desc);
  if (!p) return p.error();
  pipeline = p.value();
  Result<VkSampler> s = createNearestSampler(ctx);
  if (!s) return s.error();
  sampler = s.value();
  return metrics.init(ctx, desc.name);
}

void PassCore::retire(Context& ctx) {
  pipeline.retire(ctx);
  internal::contextImpl(ctx).retireHandle(sampler, &DeviceFunctions::vkDestroySampler);
  images.retire(ctx);
  metrics.retire(ctx);
}

std::vector<VkDescriptorSetLayoutBinding> PassCore::commonBindings() {
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  return {
      {RB_BINDING_TLAS, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, 1, rg, nullptr},
      {RB_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr},
      {RB_BINDING_NORMAL, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr},
      {RB_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr},
      {RB_BINDING_RAY_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, rg, nullptr},
  };
}

void PassCore::writeCommon(Context& ctx, DescriptorWrites& w, const GBufferDesc& g, const TlasInfo& tlas) const {
  w.accelerationStructure(RB_BINDING_TLAS, tlas.tlas);
  w.sampledImage(RB_BINDING_DEPTH, g.depth.view, sampler, readLayout(g.depth));
  w.sampledImage(RB_BINDING_NORMAL, g.normal.view, sampler, readLayout(g.normal));
  const GBufferImage& geo = g.geometricNormal.view ? g.geometricNormal : g.normal;
  w.sampledImage(RB_BINDING_GEOMETRIC_NORMAL, geo.view, sampler, readLayout(geo));
  w.storageBuffer(RB_BINDING_RAY_COUNTERS, metrics.counterBuffer(), metrics.counterOffset(ctx), metrics.counterBytes());
}

Status PassCore::begin(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g,
                       const std::vector<PassImages::Spec>& outputs) {
  if (Status s = images.ensure(ctx, g.width, g.height, outputs); !s) return s;
  metrics.beginRecording(ctx, cmd);
  metrics.writeStart(ctx, cmd);
  images.beginWrite(ctx, cmd);
  return {};
}

void PassCore::traceAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                           uint32_t constantBytes, const GBufferDesc& g) {
  pipeline.bind(ctx, cmd, w.writes, constants, constantBytes);
  pipeline.trace(ctx, cmd, g.width, g.height);
  images.endWrite(ctx, cmd);
  metrics.writeEnd(ctx, cmd);
}

}  // namespace rb
