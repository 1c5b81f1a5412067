#include "pass_core.h"

#include <string>

#include "context_impl.h"
#include "gbuffer_sampler.h"
#include "material_table_impl.h"

namespace rb {

// The material bindings and texture set of alpha testing, added to `desc` (the layout is created once, by init()).
void PassCore::addAlphaTest(RayTracingPipelineDesc& desc, SpirvModule alphaAnyHit,
                            VkShaderStageFlags recordStages) const {
  for (HitGroupDesc& g : desc.hitGroups) g.anyHit = alphaAnyHit;
  const VkShaderStageFlags stages = recordStages | VK_SHADER_STAGE_ANY_HIT_BIT_KHR;
  for (VkDescriptorSetLayoutBinding& b : desc.bindings) {
    if (b.binding == RB_BINDING_RAY_COUNTERS) b.stageFlags |= VK_SHADER_STAGE_ANY_HIT_BIT_KHR;
  }
  desc.bindings.push_back({RB_BINDING_SHADING_RECORDS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, stages, nullptr});
  desc.bindings.push_back({RB_BINDING_MATERIALS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, stages, nullptr});
  static_assert(RB_SET_TEXTURES == 1, "the texture set is the first extra set");
  desc.extraSetLayouts = {textureLayout};
}

Status PassCore::init(Context& ctx, RayTracingPipelineDesc desc, SpirvModule alphaAnyHit,
                      VkShaderStageFlags recordStages) {
  if (alphaAnyHit.code) {
    Result<VkDescriptorSetLayout> layout = createTextureSetLayout(ctx);
    if (!layout) return layout.error();
    textureLayout = layout.value();
    addAlphaTest(desc, alphaAnyHit, recordStages);
    Result<std::unique_ptr<MaterialTable>> fallback = MaterialTable::create(ctx);
    if (!fallback) return fallback.error();
    fallbackMaterials = std::move(fallback.value());
  }
  Result<RayTracingPipeline> p = RayTracingPipeline::create(ctx, desc);
  if (!p) return p.error();
  pipeline = p.value();
  Result<VkSampler> s = createNearestSampler(ctx);
  if (!s) return s.error();
  sampler = s.value();
  return metrics.init(ctx, desc.name);
}

Result<RayTracingPipeline> PassCore::createVariant(Context& ctx, RayTracingPipelineDesc desc, SpirvModule alphaAnyHit,
                                                   VkShaderStageFlags recordStages) const {
  if (alphaAnyHit.code) addAlphaTest(desc, alphaAnyHit, recordStages);
  return RayTracingPipeline::create(ctx, desc);
}

void PassCore::retire(Context& ctx) {
  pipeline.retire(ctx);
  internal::contextImpl(ctx).retireHandle(sampler, &DeviceFunctions::vkDestroySampler);
  images.retire(ctx);
  metrics.retire(ctx);
  internal::contextImpl(ctx).retireHandle(textureLayout, &DeviceFunctions::vkDestroyDescriptorSetLayout);
  fallbackMaterials.reset();  // retires its own buffer and set
}

std::vector<VkDescriptorSetLayoutBinding> PassCore::commonBindings() {
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  return {
      {RB_BINDING_TLAS, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, 1, rg, nullptr},
      {RB_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr},
      {RB_BINDING_NORMAL, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr},
      {RB_BINDING_GEOMETRIC_NORMAL, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr},
      {RB_BINDING_RAY_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, rg, nullptr},
      {RB_BINDING_REACTIVE, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr},
  };
}

void PassCore::writeCommon(Context& ctx, DescriptorWrites& w, const GBufferDesc& g, const TlasInfo& tlas) const {
  w.accelerationStructure(RB_BINDING_TLAS, tlas.tlas);
  writeGBuffer(ctx, w, g);
}

void PassCore::writeGBuffer(Context& ctx, DescriptorWrites& w, const GBufferDesc& g) const {
  w.sampledImage(RB_BINDING_DEPTH, g.depth.view, sampler, readLayout(g.depth));
  w.sampledImage(RB_BINDING_NORMAL, g.normal.view, sampler, readLayout(g.normal));
  const GBufferImage& geo = g.geometricNormal.view ? g.geometricNormal : g.normal;
  w.sampledImage(RB_BINDING_GEOMETRIC_NORMAL, geo.view, sampler, readLayout(geo));
  // Read only with RB_GB_REACTIVE (fillGBufferConstants); the depth image keeps the binding valid without a mask.
  const GBufferImage& reactive = g.reactiveMask.view ? g.reactiveMask : g.depth;
  w.sampledImage(RB_BINDING_REACTIVE, reactive.view, sampler, readLayout(reactive));
  w.storageBuffer(RB_BINDING_RAY_COUNTERS, metrics.counterBuffer(), metrics.counterOffset(ctx), metrics.counterBytes());
}

Status PassCore::writeMaterials(DescriptorWrites& w, const TlasInfo& tlas, const MaterialTable* materials,
                                const char* passName, uint32_t& gbufferFlags) {
  const MaterialTableInfo table = (materials ? materials : fallbackMaterials.get())->info();
  const bool alphaTest = materials && tlas.nonOpaqueInstances > 0;
  if (alphaTest && !tlas.shadingRecords) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 std::string(passName) + ": the TLAS has " + std::to_string(tlas.nonOpaqueInstances) +
                     " non-opaque instances but no shading records; build it with "
                     "TlasBuildOptions::writeShadingRecords = true to alpha-test them"};
  }
  if (alphaTest) gbufferFlags |= RB_GB_ALPHA_TEST;
  if (tlas.shadingRecords) {
    w.storageBuffer(RB_BINDING_SHADING_RECORDS, tlas.shadingRecords, 0, tlas.shadingRecordsBytes);
  } else {
    // Never read (no RB_GB_ALPHA_TEST, so rays are opaque), but the binding must be valid.
    w.storageBuffer(RB_BINDING_SHADING_RECORDS, table.materials, 0, table.materialBytes);
  }
  w.storageBuffer(RB_BINDING_MATERIALS, table.materials, 0, table.materialBytes);
  boundTextures = table.textures;
  return {};
}

void PassCore::bind(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                    uint32_t constantBytes, const RayTracingPipeline* variant) const {
  const RayTracingPipeline& p = variant ? *variant : pipeline;
  p.bind(ctx, cmd, w.writes, constants, constantBytes);
  if (textureLayout) {
    internal::deviceFunctions(ctx).vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR, p.layout,
                                                           RB_SET_TEXTURES, 1, &boundTextures, 0, nullptr);
  }
}

Status PassCore::prepare(Context& ctx, uint32_t width, uint32_t height, const std::vector<PassImages::Spec>& outputs,
                         const char* passName) {
  if (width == 0 || height == 0) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 std::string(passName) + "::prepare: size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is empty; pass the G-buffer's size"};
  }
  return images.ensure(ctx, width, height, outputs);
}

Status PassCore::begin(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g,
                       const std::vector<PassImages::Spec>& outputs) {
  if (Status s = images.ensure(ctx, g.width, g.height, outputs); !s) return s;
  if (Status s = metrics.beginRecording(ctx, cmd); !s) return s;
  metrics.writeStart(ctx, cmd);
  images.beginWrite(ctx, cmd);
  return {};
}

void PassCore::traceAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                           uint32_t constantBytes, const GBufferDesc& g, const RayTracingPipeline* variant) {
  bind(ctx, cmd, w, constants, constantBytes, variant);
  (variant ? *variant : pipeline).trace(ctx, cmd, g.width, g.height);
  end(ctx, cmd);
}

void PassCore::traceHalfAndEnd(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                               uint32_t constantBytes, const GBufferConstants& traced, const GBufferDesc& g,
                               HalfResolution& half, float roughnessThreshold, const RayTracingPipeline* variant) {
  half.beginTrace(ctx, cmd);
  bind(ctx, cmd, w, constants, constantBytes, variant);
  (variant ? *variant : pipeline).trace(ctx, cmd, half.width(), half.height());
  half.upsample(ctx, cmd, g, sampler, traced, roughnessThreshold, images[0].view);
  end(ctx, cmd);
}

void PassCore::end(Context& ctx, VkCommandBuffer cmd) {
  images.endWrite(ctx, cmd);
  metrics.writeEnd(ctx, cmd);
}

}  // namespace rb
