#include "compute_pipeline.h"

#include <string>

#include "context_impl.h"

namespace rb {

Result<ComputePipeline> ComputePipeline::create(Context& ctx, const SpirvModule& shader,
                                                const std::vector<VkDescriptorSetLayoutBinding>& bindings,
                                                uint32_t pushConstantBytes, const char* name) {
  Context::Impl& c = internal::contextImpl(ctx);
  ComputePipeline p;
  VkDescriptorSetLayoutCreateInfo sl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  sl.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  sl.bindingCount = static_cast<uint32_t>(bindings.size());
  sl.pBindings = bindings.data();
  VkResult r = c.vk.vkCreateDescriptorSetLayout(c.desc.device, &sl, c.allocator(), &p.setLayout);
  if (r != VK_SUCCESS) return vulkanError(r, std::string("vkCreateDescriptorSetLayout for ") + name);
  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, pushConstantBytes};
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &p.setLayout;
  pl.pushConstantRangeCount = pushConstantBytes ? 1 : 0;
  pl.pPushConstantRanges = &range;
  r = c.vk.vkCreatePipelineLayout(c.desc.device, &pl, c.allocator(), &p.layout);
  if (r != VK_SUCCESS) {
    p.layout = VK_NULL_HANDLE;  // undefined after a failed create
    p.destroy(ctx);
    return vulkanError(r, std::string("vkCreatePipelineLayout for ") + name);
  }
  VkShaderModuleCreateInfo mi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  mi.codeSize = shader.bytes;
  mi.pCode = shader.code;
  VkShaderModule module = VK_NULL_HANDLE;
  r = c.vk.vkCreateShaderModule(c.desc.device, &mi, c.allocator(), &module);
  if (r != VK_SUCCESS) {
    p.destroy(ctx);
    return vulkanError(r, std::string("vkCreateShaderModule for ") + name);
  }
  VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  ci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = module;
  ci.stage.pName = "main";
  ci.layout = p.layout;
  r = c.vk.vkCreateComputePipelines(c.desc.device, VK_NULL_HANDLE, 1, &ci, c.allocator(), &p.pipeline);
  c.vk.vkDestroyShaderModule(c.desc.device, module, c.allocator());
  if (r != VK_SUCCESS) {
    p.destroy(ctx);
    return vulkanError(r, std::string("vkCreateComputePipelines for ") + name);
  }
  return p;
}

void ComputePipeline::destroy(Context& ctx) {
  Context::Impl& c = internal::contextImpl(ctx);
  if (pipeline) c.vk.vkDestroyPipeline(c.desc.device, pipeline, c.allocator());
  if (layout) c.vk.vkDestroyPipelineLayout(c.desc.device, layout, c.allocator());
  if (setLayout) c.vk.vkDestroyDescriptorSetLayout(c.desc.device, setLayout, c.allocator());
  pipeline = VK_NULL_HANDLE;
  layout = VK_NULL_HANDLE;
  setLayout = VK_NULL_HANDLE;
}

void ComputePipeline::retire(Context& ctx) {
  if (!pipeline && !layout && !setLayout) return;
  ComputePipeline retired = *this;
  *this = ComputePipeline{};
  Context* context = &ctx;
  internal::contextImpl(ctx).retire([context, retired]() mutable { retired.destroy(*context); });
}

void ComputePipeline::dispatch(Context& ctx, VkCommandBuffer cmd, std::span<const VkWriteDescriptorSet> writes,
                               const void* constants, uint32_t constantBytes, uint32_t width, uint32_t height,
                               uint32_t groupSide) const {
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  vk.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline);
  vk.vkCmdPushDescriptorSetKHR(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, static_cast<uint32_t>(writes.size()),
                               writes.data());
  if (constantBytes) vk.vkCmdPushConstants(cmd, layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, constantBytes, constants);
  vk.vkCmdDispatch(cmd, (width + groupSide - 1) / groupSide, (height + groupSide - 1) / groupSide, 1);
}

}  // namespace rb
