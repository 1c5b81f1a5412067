// The viewer's backdrop: see viewer_backdrop.h.
#include "viewer_backdrop.h"

#include <string>
#include <type_traits>
#include <vector>

#include "viewer_shaders.h"

namespace se = sample_engine;

namespace rbViewer {

namespace {

// What shaders/backdrop.frag reads.
struct BackdropConstants {
  int32_t channel;
  float scale;
  uint32_t compressHdr;
};

}  // namespace

struct Backdrop::Impl {
  std::string error;
  bool started = false;

  // Loaded through the engine's vkGetInstanceProcAddr on the first draw (no loader globals, as the overlay).
  VkDevice device = VK_NULL_HANDLE;
  PFN_vkCreateSampler createSampler = nullptr;
  PFN_vkDestroySampler destroySampler = nullptr;
  PFN_vkCreateDescriptorSetLayout createDescriptorSetLayout = nullptr;
  PFN_vkDestroyDescriptorSetLayout destroyDescriptorSetLayout = nullptr;
  PFN_vkCreateDescriptorPool createDescriptorPool = nullptr;
  PFN_vkDestroyDescriptorPool destroyDescriptorPool = nullptr;
  PFN_vkAllocateDescriptorSets allocateDescriptorSets = nullptr;
  PFN_vkUpdateDescriptorSets updateDescriptorSets = nullptr;
  PFN_vkCreatePipelineLayout createPipelineLayout = nullptr;
  PFN_vkDestroyPipelineLayout destroyPipelineLayout = nullptr;
  PFN_vkCreateShaderModule createShaderModule = nullptr;
  PFN_vkDestroyShaderModule destroyShaderModule = nullptr;
  PFN_vkCreateGraphicsPipelines createGraphicsPipelines = nullptr;
  PFN_vkDestroyPipeline destroyPipeline = nullptr;
  PFN_vkCmdBeginRenderPass cmdBeginRenderPass = nullptr;
  PFN_vkCmdEndRenderPass cmdEndRenderPass = nullptr;
  PFN_vkCmdBindPipeline cmdBindPipeline = nullptr;
  PFN_vkCmdBindDescriptorSets cmdBindDescriptorSets = nullptr;
  PFN_vkCmdPushConstants cmdPushConstants = nullptr;
  PFN_vkCmdSetViewport cmdSetViewport = nullptr;
  PFN_vkCmdSetScissor cmdSetScissor = nullptr;
  PFN_vkCmdDraw cmdDraw = nullptr;
  PFN_vkCmdPipelineBarrier cmdPipelineBarrier = nullptr;

  VkSampler sampler = VK_NULL_HANDLE;
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  std::vector<VkDescriptorSet> sets;  // one per frame in flight, indexed by OverlayHookInfo::frameIndex
  VkPipelineLayout pipelineLayout = VK_NULL_HANDLE;
  VkPipeline pipeline = VK_NULL_HANDLE;

  bool loadFunctions(const se::OverlayHookInfo& info);
  bool check(VkResult r, const char* what) {
    if (r == VK_SUCCESS) return true;
    error = std::string(what) + " failed (VkResult " + std::to_string(int(r)) + ")";
    return false;
  }
  bool start(const se::OverlayHookInfo& info);
  bool createDescriptors(uint32_t framesInFlight);
  bool createPipeline(VkRenderPass renderPass);
  void draw(const se::OverlayHookInfo& info, const BackdropImage& image);
};

bool Backdrop::Impl::loadFunctions(const se::OverlayHookInfo& info) {
  device = info.device;
  auto getDeviceProcAddr = reinterpret_cast<PFN_vkGetDeviceProcAddr>(
      info.getInstanceProcAddr(info.instance, "vkGetDeviceProcAddr"));
  if (!getDeviceProcAddr) return error = "vkGetDeviceProcAddr not found", false;
  bool found = true;
  auto load = [&](auto& f, const char* name) {
    f = reinterpret_cast<std::remove_reference_t<decltype(f)>>(getDeviceProcAddr(device, name));
    found = found && f;
  };
  load(createSampler, "vkCreateSampler");
  load(destroySampler, "vkDestroySampler");
  load(createDescriptorSetLayout, "vkCreateDescriptorSetLayout");
  load(destroyDescriptorSetLayout, "vkDestroyDescriptorSetLayout");
  load(createDescriptorPool, "vkCreateDescriptorPool");
  load(destroyDescriptorPool, "vkDestroyDescriptorPool");
  load(allocateDescriptorSets, "vkAllocateDescriptorSets");
  load(updateDescriptorSets, "vkUpdateDescriptorSets");
  load(createPipelineLayout, "vkCreatePipelineLayout");
  load(destroyPipelineLayout, "vkDestroyPipelineLayout");
  load(createShaderModule, "vkCreateShaderModule");
  load(destroyShaderModule, "vkDestroyShaderModule");
  load(createGraphicsPipelines, "vkCreateGraphicsPipelines");
  load(destroyPipeline, "vkDestroyPipeline");
  load(cmdBeginRenderPass, "vkCmdBeginRenderPass");
  load(cmdEndRenderPass, "vkCmdEndRenderPass");
  load(cmdBindPipeline, "vkCmdBindPipeline");
  load(cmdBindDescriptorSets, "vkCmdBindDescriptorSets");
  load(cmdPushConstants, "vkCmdPushConstants");
  load(cmdSetViewport, "vkCmdSetViewport");
  load(cmdSetScissor, "vkCmdSetScissor");
  load(cmdDraw, "vkCmdDraw");
  load(cmdPipelineBarrier, "vkCmdPipelineBarrier");
  if (!found) error = "the device lacks a core Vulkan 1.0 function";
  return found;
}

bool Backdrop::Impl::createDescriptors(uint32_t framesInFlight) {
  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = sci.minFilter = VK_FILTER_NEAREST;  // a debug view shows texels as they are
  sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  if (!check(createSampler(device, &sci, nullptr, &sampler), "vkCreateSampler")) return false;

  VkDescriptorSetLayoutBinding binding{};
  binding.binding = 0;
  binding.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  binding.descriptorCount = 1;
  binding.stageFlags = VK_SHADER_STAGE_FRAGMENT_BIT;
  binding.pImmutableSamplers = &sampler;
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = 1;
  lci.pBindings = &binding;
  if (!check(createDescriptorSetLayout(device, &lci, nullptr, &setLayout), "vkCreateDescriptorSetLayout")) return false;

  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, framesInFlight};
  VkDescriptorPoolCreateInfo pci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pci.maxSets = framesInFlight;
  pci.poolSizeCount = 1;
  pci.pPoolSizes = &size;
  if (!check(createDescriptorPool(device, &pci, nullptr, &pool), "vkCreateDescriptorPool")) return false;
  const std::vector<VkDescriptorSetLayout> layouts(framesInFlight, setLayout);
  sets.assign(framesInFlight, VK_NULL_HANDLE);
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = pool;
  ai.descriptorSetCount = framesInFlight;
  ai.pSetLayouts = layouts.data();
  return check(allocateDescriptorSets(device, &ai, sets.data()), "vkAllocateDescriptorSets");
}

bool Backdrop::Impl::createPipeline(VkRenderPass renderPass) {
  VkPushConstantRange range{VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(BackdropConstants)};
  VkPipelineLayoutCreateInfo lci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  lci.setLayoutCount = 1;
  lci.pSetLayouts = &setLayout;
  lci.pushConstantRangeCount = 1;
  lci.pPushConstantRanges = &range;
  if (!check(createPipelineLayout(device, &lci, nullptr, &pipelineLayout), "vkCreatePipelineLayout")) return false;

  VkShaderModule modules[2] = {};
  auto module = [&](const uint32_t* code, size_t bytes, VkShaderModule& m) {
    VkShaderModuleCreateInfo mci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    mci.codeSize = bytes;
    mci.pCode = code;
    return check(createShaderModule(device, &mci, nullptr, &m), "vkCreateShaderModule");
  };
  bool ok = module(spirv::backdrop_vert, sizeof spirv::backdrop_vert, modules[0]) &&
            module(spirv::backdrop_frag, sizeof spirv::backdrop_frag, modules[1]);
  if (ok) {
    VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
                                                 {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = modules[0];
    stages[0].pName = "main";
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = modules[1];
    stages[1].pName = "main";
    VkPipelineVertexInputStateCreateInfo vertexInput{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    viewport.viewportCount = viewport.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    raster.polygonMode = VK_POLYGON_MODE_FILL;
    raster.cullMode = VK_CULL_MODE_NONE;
    raster.lineWidth = 1.0f;
    VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineColorBlendAttachmentState attachment{};  // no blending: the backdrop replaces the frame
    attachment.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT |
                                VK_COLOR_COMPONENT_A_BIT;
    VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    blend.attachmentCount = 1;
    blend.pAttachments = &attachment;
    const VkDynamicState dynamicStates[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    dynamic.dynamicStateCount = 2;
    dynamic.pDynamicStates = dynamicStates;
    VkGraphicsPipelineCreateInfo gci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    gci.stageCount = 2;
    gci.pStages = stages;
    gci.pVertexInputState = &vertexInput;
    gci.pInputAssemblyState = &assembly;
    gci.pViewportState = &viewport;
    gci.pRasterizationState = &raster;
    gci.pMultisampleState = &multisample;
    gci.pColorBlendState = &blend;
    gci.pDynamicState = &dynamic;
    gci.layout = pipelineLayout;
    gci.renderPass = renderPass;
    gci.subpass = 0;
    ok = check(createGraphicsPipelines(device, VK_NULL_HANDLE, 1, &gci, nullptr, &pipeline),
               "vkCreateGraphicsPipelines");
  }
  for (VkShaderModule m : modules)
    if (m) destroyShaderModule(device, m, nullptr);
  return ok;
}

bool Backdrop::Impl::start(const se::OverlayHookInfo& info) {
  started = true;
  return loadFunctions(info) && createDescriptors(info.framesInFlight) && createPipeline(info.renderPass);
}

void Backdrop::Impl::draw(const se::OverlayHookInfo& info, const BackdropImage& image) {
  // The frame that last bound this slot's set has finished (OverlayHookInfo::framesInFlight), so it is free.
  const VkDescriptorSet set = sets[info.frameIndex];
  VkDescriptorImageInfo imageInfo{VK_NULL_HANDLE, image.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  write.dstSet = set;
  write.dstBinding = 0;
  write.descriptorCount = 1;
  write.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  write.pImageInfo = &imageInfo;
  updateDescriptorSets(device, 1, &write, 0, nullptr);

  const VkCommandBuffer cmd = info.commandBuffer;
  VkRenderPassBeginInfo rbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rbi.renderPass = info.renderPass;
  rbi.framebuffer = info.framebuffer;
  rbi.renderArea = {{0, 0}, info.extent};
  cmdBeginRenderPass(cmd, &rbi, VK_SUBPASS_CONTENTS_INLINE);
  cmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
  const VkViewport viewport{0.0f, 0.0f, float(info.extent.width), float(info.extent.height), 0.0f, 1.0f};
  cmdSetViewport(cmd, 0, 1, &viewport);
  cmdSetScissor(cmd, 0, 1, &rbi.renderArea);
  cmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelineLayout, 0, 1, &set, 0, nullptr);
  const BackdropConstants constants{int32_t(image.channel), image.scale, image.compressHdr ? 1u : 0u};
  cmdPushConstants(cmd, pipelineLayout, VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof constants, &constants);
  cmdDraw(cmd, 3, 1, 0, 0);
  cmdEndRenderPass(cmd);
  // The overlay's render pass has no dependency of its own: the next pass drawing into the target (the UI) must
  // see these writes.
  VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  barrier.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  barrier.dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
  cmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                     0, 1, &barrier, 0, nullptr, 0, nullptr);
}

Backdrop::Backdrop() : impl_(std::make_unique<Impl>()) {}

Backdrop::~Backdrop() {
  Impl& s = *impl_;
  if (!s.device) return;
  // Only what was made: a failed start leaves the rest VK_NULL_HANDLE (the pool frees its sets).
  if (s.pipeline) s.destroyPipeline(s.device, s.pipeline, nullptr);
  if (s.pipelineLayout) s.destroyPipelineLayout(s.device, s.pipelineLayout, nullptr);
  if (s.pool) s.destroyDescriptorPool(s.device, s.pool, nullptr);
  if (s.setLayout) s.destroyDescriptorSetLayout(s.device, s.setLayout, nullptr);
  if (s.sampler) s.destroySampler(s.device, s.sampler, nullptr);
}

void Backdrop::record(const se::OverlayHookInfo& info, const BackdropImage& image) {
  Impl& s = *impl_;
  if (!image.view || !s.error.empty()) return;
  if (!s.started && !s.start(info)) return;
  if (info.frameIndex >= s.sets.size()) {
    s.error = "frame slot " + std::to_string(info.frameIndex) + " beyond the " + std::to_string(s.sets.size()) +
              " frames in flight of the first frame";
    return;
  }
  s.draw(info, image);
}

const std::string& Backdrop::lastError() const { return impl_->error; }

}  // namespace rbViewer
