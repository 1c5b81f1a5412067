#include "ray_tracing_pipeline.h"

#include <cstring>
#include <string>

#include "align_up.h"
#include "context_impl.h"

namespace rb {

namespace {


Result<VkShaderModule> makeModule(Context::Impl& c, const SpirvModule& m, const char* name) {
  VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  info.codeSize = m.bytes;
  info.pCode = m.code;
  VkShaderModule module = VK_NULL_HANDLE;
  VkResult r = c.vk.vkCreateShaderModule(c.desc.device, &info, c.allocator(), &module);
  if (r != VK_SUCCESS) return vulkanError(r, std::string("vkCreateShaderModule for ") + name);
  return module;
}

// The shader binding table of `p` (created): raygen | misses | hit groups, each region starting at the base
// alignment, in a host-visible buffer; the caller destroys `p` on an error.
Status writeShaderBindingTable(Context& ctx, RayTracingPipeline& p, uint32_t groupCount, uint32_t missCount,
                               uint32_t hitCount) {
  Context::Impl& c = internal::contextImpl(ctx);
  const uint32_t handleSize = c.info.shaderGroupHandleSize;
  const VkDeviceSize stride = alignUp(handleSize, c.info.shaderGroupHandleAlignment);
  const VkDeviceSize base = c.info.shaderGroupBaseAlignment;
  std::vector<uint8_t> handles(size_t(groupCount) * handleSize);
  VkResult r = c.vk.vkGetRayTracingShaderGroupHandlesKHR(c.desc.device, p.pipeline, 0, groupCount, handles.size(),
                                                         handles.data());
  if (r != VK_SUCCESS) return vulkanError(r, "vkGetRayTracingShaderGroupHandlesKHR");
  VkDeviceSize raygenSize = alignUp(stride, base);
  VkDeviceSize missSize = alignUp(stride * missCount, base);
  VkDeviceSize hitSize = alignUp(stride * hitCount, base);
  Result<GpuBuffer> sbt =
      createBuffer(ctx, raygenSize + missSize + hitSize + base,
                   VK_BUFFER_USAGE_SHADER_BINDING_TABLE_BIT_KHR | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                   MemoryLocation::HostVisibleDeviceLocal, MemoryCategory::ShaderTables, "shader binding table");
  if (!sbt) return sbt.error();
  p.sbt = sbt.value();
  VkDeviceAddress start = alignUp(p.sbt.address, base);
  auto* bytes = static_cast<uint8_t*>(p.sbt.mapped) + (start - p.sbt.address);
  std::memcpy(bytes, handles.data(), handleSize);
  for (uint32_t i = 0; i < missCount; ++i) {
    std::memcpy(bytes + raygenSize + i * stride, handles.data() + (1 + i) * handleSize, handleSize);
  }
  for (uint32_t i = 0; i < hitCount; ++i) {
    std::memcpy(bytes + raygenSize + missSize + i * stride, handles.data() + (1 + missCount + i) * handleSize,
                handleSize);
  }
  p.raygenRegion = {start, raygenSize, raygenSize};
  p.missRegion = {start + raygenSize, stride, stride * missCount};
  p.hitRegion = {start + raygenSize + missSize, stride, stride * hitCount};
  if (missCount == 0) p.missRegion = {};
  if (hitCount == 0) p.hitRegion = {};
  return {};
}

}  // namespace

Result<RayTracingPipeline> RayTracingPipeline::create(Context& ctx, const RayTracingPipelineDesc& desc) {
  Context::Impl& c = internal::contextImpl(ctx);
  RayTracingPipeline p;
  VkDescriptorSetLayoutCreateInfo sl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  sl.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  sl.bindingCount = static_cast<uint32_t>(desc.bindings.size());
  sl.pBindings = desc.bindings.data();
  VkResult r = c.vk.vkCreateDescriptorSetLayout(c.desc.device, &sl, c.allocator(), &p.setLayout);
  if (r != VK_SUCCESS) return vulkanError(r, std::string("vkCreateDescriptorSetLayout for ") + desc.name);

  p.pushConstantStages = VK_SHADER_STAGE_RAYGEN_BIT_KHR | VK_SHADER_STAGE_MISS_BIT_KHR |
                         VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR | VK_SHADER_STAGE_ANY_HIT_BIT_KHR;
  VkPushConstantRange range{p.pushConstantStages, 0, desc.pushConstantBytes};
  std::vector<VkDescriptorSetLayout> setLayouts = {p.setLayout};
  setLayouts.insert(setLayouts.end(), desc.extraSetLayouts.begin(), desc.extraSetLayouts.end());
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = static_cast<uint32_t>(setLayouts.size());
  pl.pSetLayouts = setLayouts.data();
  pl.pushConstantRangeCount = desc.pushConstantBytes ? 1 : 0;
  pl.pPushConstantRanges = &range;
  r = c.vk.vkCreatePipelineLayout(c.desc.device, &pl, c.allocator(), &p.layout);
  if (r != VK_SUCCESS) {
    p.layout = VK_NULL_HANDLE;  // undefined after a failed create
    p.destroy(ctx);
    return vulkanError(r, std::string("vkCreatePipelineLayout for ") + desc.name);
  }

  std::vector<VkPipelineShaderStageCreateInfo> stages;
  std::vector<VkRayTracingShaderGroupCreateInfoKHR> groups;
  std::vector<VkShaderModule> modules;
  auto addStage = [&](const SpirvModule& m, VkShaderStageFlagBits stage) -> Result<uint32_t> {
    Result<VkShaderModule> mod = makeModule(c, m, desc.name);
    if (!mod) return mod.error();
    modules.push_back(mod.value());
    VkPipelineShaderStageCreateInfo s{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    s.stage = stage;
    s.module = mod.value();
    s.pName = "main";
    stages.push_back(s);
    return static_cast<uint32_t>(stages.size() - 1);
  };
  auto general = [](uint32_t stage) {
    VkRayTracingShaderGroupCreateInfoKHR g{VK_STRUCTURE_TYPE_RAY_TRACING_SHADER_GROUP_CREATE_INFO_KHR};
    g.type = VK_RAY_TRACING_SHADER_GROUP_TYPE_GENERAL_KHR;
    g.generalShader = stage;
    g.closestHitShader = g.anyHitShader = g.intersectionShader = VK_SHADER_UNUSED_KHR;
    return g;
  };
  Status status;
  auto cleanupModules = [&] {
    for (VkShaderModule m : modules) c.vk.vkDestroyShaderModule(c.desc.device, m, c.allocator());
  };
  {
    Result<uint32_t> s = addStage(desc.raygen, VK_SHADER_STAGE_RAYGEN_BIT_KHR);
    if (!s) status = s.error();
    else
      groups.push_back(general(s.value()));
  }
  for (const SpirvModule& miss : desc.misses) {
    if (!status) break;
    Result<uint32_t> s = addStage(miss, VK_SHADER_STAGE_MISS_BIT_KHR);
    if (!s) status = s.error();
    else
      groups.push_back(general(s.value()));
  }
  for (const HitGroupDesc& hg : desc.hitGroups) {
    if (!status) break;
    VkRayTracingShaderGroupCreateInfoKHR g{VK_STRUCTURE_TYPE_RAY_TRACING_SHADER_GROUP_CREATE_INFO_KHR};
    g.type = VK_RAY_TRACING_SHADER_GROUP_TYPE_TRIANGLES_HIT_GROUP_KHR;
    g.generalShader = g.closestHitShader = g.anyHitShader = g.intersectionShader = VK_SHADER_UNUSED_KHR;
    if (hg.closestHit.code) {
      Result<uint32_t> s = addStage(hg.closestHit, VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR);
      if (!s) {
        status = s.error();
        break;
      }
      g.closestHitShader = s.value();
    }
    if (hg.anyHit.code) {
      Result<uint32_t> s = addStage(hg.anyHit, VK_SHADER_STAGE_ANY_HIT_BIT_KHR);
      if (!s) {
        status = s.error();
        break;
      }
      g.anyHitShader = s.value();
    }
    groups.push_back(g);
  }
  if (!status) {
    cleanupModules();
    p.destroy(ctx);
    return status.error();
  }

  VkRayTracingPipelineCreateInfoKHR info{VK_STRUCTURE_TYPE_RAY_TRACING_PIPELINE_CREATE_INFO_KHR};
  info.stageCount = static_cast<uint32_t>(stages.size());
  info.pStages = stages.data();
  info.groupCount = static_cast<uint32_t>(groups.size());
  info.pGroups = groups.data();
  info.maxPipelineRayRecursionDepth = desc.maxRecursionDepth;
  info.layout = p.layout;
  r = c.vk.vkCreateRayTracingPipelinesKHR(c.desc.device, VK_NULL_HANDLE, VK_NULL_HANDLE, 1, &info, c.allocator(),
                                          &p.pipeline);
  cleanupModules();
  if (r != VK_SUCCESS) {
    p.destroy(ctx);
    return vulkanError(r, std::string("vkCreateRayTracingPipelinesKHR for ") + desc.name);
  }

  if (Status st = writeShaderBindingTable(ctx, p, uint32_t(groups.size()), uint32_t(desc.misses.size()),
                                          uint32_t(desc.hitGroups.size()));
      !st) {
    p.destroy(ctx);
    return st.error();
  }
  return p;
}

void RayTracingPipeline::destroy(Context& ctx) {
  Context::Impl& c = internal::contextImpl(ctx);
  if (pipeline) c.vk.vkDestroyPipeline(c.desc.device, pipeline, c.allocator());
  if (layout) c.vk.vkDestroyPipelineLayout(c.desc.device, layout, c.allocator());
  if (setLayout) c.vk.vkDestroyDescriptorSetLayout(c.desc.device, setLayout, c.allocator());
  destroyBuffer(ctx, sbt);
  pipeline = VK_NULL_HANDLE;
  layout = VK_NULL_HANDLE;
  setLayout = VK_NULL_HANDLE;
}

void RayTracingPipeline::retire(Context& ctx) {
  if (!pipeline && !layout && !setLayout && !sbt.valid()) return;
  RayTracingPipeline retired = *this;
  *this = RayTracingPipeline{};
  Context* context = &ctx;
  internal::contextImpl(ctx).retire([context, retired]() mutable { retired.destroy(*context); });
}

void RayTracingPipeline::bind(Context& ctx, VkCommandBuffer cmd, std::span<const VkWriteDescriptorSet> writes,
                              const void* constants, uint32_t constantBytes) const {
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  vk.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR, pipeline);
  vk.vkCmdPushDescriptorSetKHR(cmd, VK_PIPELINE_BIND_POINT_RAY_TRACING_KHR, layout, 0,
                               static_cast<uint32_t>(writes.size()), writes.data());
  if (constantBytes) vk.vkCmdPushConstants(cmd, layout, pushConstantStages, 0, constantBytes, constants);
}

void RayTracingPipeline::trace(Context& ctx, VkCommandBuffer cmd, uint32_t width, uint32_t height,
                               uint32_t depth) const {
  internal::deviceFunctions(ctx).vkCmdTraceRaysKHR(cmd, &raygenRegion, &missRegion, &hitRegion, &callableRegion, width,
                                                   height, depth);
}

void RayTracingPipeline::traceIndirect(Context& ctx, VkCommandBuffer cmd, VkDeviceAddress arguments) const {
  internal::deviceFunctions(ctx).vkCmdTraceRaysIndirectKHR(cmd, &raygenRegion, &missRegion, &hitRegion, &callableRegion,
                                                           arguments);
}

namespace {
VkWriteDescriptorSet write(uint32_t binding, VkDescriptorType type) {
  VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  w.dstBinding = binding;
  w.descriptorCount = 1;
  w.descriptorType = type;
  return w;
}
}  // namespace

void DescriptorWrites::accelerationStructure(uint32_t binding, VkAccelerationStructureKHR as) {
  accelHandles.push_back(as);
  VkWriteDescriptorSetAccelerationStructureKHR a{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET_ACCELERATION_STRUCTURE_KHR};
  a.accelerationStructureCount = 1;
  a.pAccelerationStructures = &accelHandles.back();
  accels.push_back(a);
  VkWriteDescriptorSet w = write(binding, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR);
  w.pNext = &accels.back();
  writes.push_back(w);
}

void DescriptorWrites::storageImage(uint32_t binding, VkImageView view, VkImageLayout layout) {
  images.push_back({VK_NULL_HANDLE, view, layout});
  VkWriteDescriptorSet w = write(binding, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE);
  w.pImageInfo = &images.back();
  writes.push_back(w);
}

void DescriptorWrites::sampledImage(uint32_t binding, VkImageView view, VkSampler sampler, VkImageLayout layout) {
  images.push_back({sampler, view, layout});
  VkWriteDescriptorSet w = write(binding, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER);
  w.pImageInfo = &images.back();
  writes.push_back(w);
}

void DescriptorWrites::storageBuffer(uint32_t binding, VkBuffer buffer, VkDeviceSize offset, VkDeviceSize range) {
  buffers.push_back({buffer, offset, range});
  VkWriteDescriptorSet w = write(binding, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
  w.pBufferInfo = &buffers.back();
  writes.push_back(w);
}

}  // namespace rb
