#include "half_resolution.h"

#include "raybridge_shaders.h"

namespace rb {

Status HalfResolution::ensure(Context& ctx, uint32_t width, uint32_t height) {
  const bool reflection = signal_ == Signal::Reflection;
  if (!pipeline_.pipeline) {
    const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
    auto sampled = [&](uint32_t b) {
      return VkDescriptorSetLayoutBinding{b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, cs, nullptr};
    };
    std::vector<VkDescriptorSetLayoutBinding> bindings = {sampled(RB_UPSAMPLE_BINDING_DEPTH),
                                                          sampled(RB_UPSAMPLE_BINDING_NORMAL),
                                                          sampled(RB_UPSAMPLE_BINDING_SAMPLES),
                                                          {RB_UPSAMPLE_BINDING_OUTPUT, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
                                                           1, cs, nullptr}};
    if (reflection) bindings.push_back(sampled(RB_UPSAMPLE_BINDING_ROUGHNESS_METALNESS));
    Result<ComputePipeline> p =
        reflection ? ComputePipeline::create(ctx, SpirvModule::of(spirv::upsample_depth_aware_reflection_comp),
                                             bindings, sizeof(UpsampleConstants), "reflection upsample")
                   : ComputePipeline::create(ctx, SpirvModule::of(spirv::upsample_depth_aware_ao_comp), bindings,
                                             sizeof(UpsampleConstants), "AO upsample");
    if (!p) return p.error();
    pipeline_ = p.value();
  }
  const PassImages::Spec spec = reflection ? PassImages::Spec{VK_FORMAT_R16G16B16A16_SFLOAT,
                                                              "reflection half-resolution samples"}
                                           : PassImages::Spec{VK_FORMAT_R16_SFLOAT, "AO half-resolution samples"};
  return images_.ensure(ctx, (width + 1) / 2, (height + 1) / 2, {spec});
}

void HalfResolution::releaseImage(Context& ctx) { images_.retire(ctx); }

void HalfResolution::retire(Context& ctx) {
  images_.retire(ctx);
  pipeline_.retire(ctx);
}

void HalfResolution::upsample(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, VkSampler sampler,
                              const GBufferConstants& traced, float roughnessThreshold, VkImageView output) {
  images_.endWrite(ctx, cmd);  // the ray generation shader's samples, for the compute shader
  UpsampleConstants pc{};
  pc.gbuffer = traced;
  pc.roughnessThreshold = roughnessThreshold;
  DescriptorWrites w;
  w.sampledImage(RB_UPSAMPLE_BINDING_DEPTH, g.depth.view, sampler, readLayout(g.depth));
  w.sampledImage(RB_UPSAMPLE_BINDING_NORMAL, g.normal.view, sampler, readLayout(g.normal));
  w.sampledImage(RB_UPSAMPLE_BINDING_SAMPLES, images_[0].view, sampler, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  w.storageImage(RB_UPSAMPLE_BINDING_OUTPUT, output);
  if (signal_ == Signal::Reflection) {
    const GBufferImage& rm = g.roughnessMetalness.view ? g.roughnessMetalness : g.normal;
    w.sampledImage(RB_UPSAMPLE_BINDING_ROUGHNESS_METALNESS, rm.view, sampler, readLayout(rm));
  }
  pipeline_.dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height);
}

}  // namespace rb
