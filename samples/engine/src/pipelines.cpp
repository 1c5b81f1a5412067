#include "pipelines.h"

#include <vector>

#include "engine_shaders.h"
#include "vk_check.h"

namespace sample_engine::detail {
namespace {

template <size_t N>
std::string makeModule(VkDevice device, const uint32_t (&code)[N], VkShaderModule& out) {
  VkShaderModuleCreateInfo ci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  ci.codeSize = N * sizeof(uint32_t);
  ci.pCode = code;
  SE_VK_TRY(vkCreateShaderModule(device, &ci, nullptr, &out));
  return {};
}

std::string makeSetLayout(VkDevice device, std::vector<VkDescriptorSetLayoutBinding> bindings,
                          VkDescriptorSetLayout& out) {
  VkDescriptorSetLayoutCreateInfo ci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  ci.bindingCount = uint32_t(bindings.size());
  ci.pBindings = bindings.data();
  SE_VK_TRY(vkCreateDescriptorSetLayout(device, &ci, nullptr, &out));
  return {};
}

VkDescriptorSetLayoutBinding samplerBinding(uint32_t binding) {
  return {binding, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_FRAGMENT_BIT, nullptr};
}

VkDescriptorSetLayoutBinding computeBinding(uint32_t binding, VkDescriptorType type) {
  return {binding, type, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
}

std::string makeComputePipeline(VkDevice device, VkShaderModule module, VkPipelineLayout layout, VkPipeline& out) {
  VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  ci.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = module;
  ci.stage.pName = "main";
  ci.layout = layout;
  SE_VK_TRY(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &ci, nullptr, &out));
  return {};
}

VkDescriptorSetLayoutBinding bufferBinding(uint32_t binding, VkDescriptorType type) {
  return {binding, type, 1, VK_SHADER_STAGE_FRAGMENT_BIT, nullptr};
}

enum class VertexInput {
  None,          // fullscreen passes
  Positions,     // binding 0 only
  PositionsUvs,  // binding 0 + the UV of binding 1 (location 2)
  Full,          // positions (binding 0) + attributes (binding 1) + last frame's positions (binding 2)
};

struct PipelineDesc {
  VkShaderModule vert = VK_NULL_HANDLE;
  VkShaderModule frag = VK_NULL_HANDLE;
  VertexInput vertices = VertexInput::Full;
  std::vector<VkFormat> colorFormats;
  VkFormat depthFormat = VK_FORMAT_UNDEFINED;
  bool depthTest = false, depthWrite = false;
  VkCompareOp depthCompare = VK_COMPARE_OP_LESS;
  bool depthBias = false;
  bool dynamicCulling = false;  // cull mode and front face set per draw (else: no culling)
  bool alphaTested = false;     // fragment specialization constant 0 (kAlphaTested in surface.glsl)
  bool blend = false;           // colour = src * src alpha + dst * (1 - src alpha)
  VkPipelineLayout layout = VK_NULL_HANDLE;
};

std::string makePipeline(VkDevice device, const PipelineDesc& d, VkPipeline& out) {
  const VkBool32 alphaTested = d.alphaTested;
  const VkSpecializationMapEntry alphaTestedEntry{0, 0, sizeof(VkBool32)};
  const VkSpecializationInfo specialization{1, &alphaTestedEntry, sizeof(alphaTested), &alphaTested};
  std::vector<VkPipelineShaderStageCreateInfo> stages;
  stages.push_back({VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_VERTEX_BIT, d.vert,
                    "main", nullptr});
  if (d.frag)
    stages.push_back({VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_FRAGMENT_BIT,
                      d.frag, "main", d.alphaTested ? &specialization : nullptr});
  std::vector<VkVertexInputBindingDescription> bindings;
  std::vector<VkVertexInputAttributeDescription> attributes;
  if (d.vertices != VertexInput::None) {
    bindings.push_back({0, 12, VK_VERTEX_INPUT_RATE_VERTEX});
    attributes.push_back({0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0});
  }
  if (d.vertices == VertexInput::PositionsUvs || d.vertices == VertexInput::Full)
    bindings.push_back({1, 36, VK_VERTEX_INPUT_RATE_VERTEX});
  if (d.vertices == VertexInput::Full) attributes.push_back({1, 1, VK_FORMAT_R32G32B32_SFLOAT, 0});
  if (d.vertices == VertexInput::PositionsUvs || d.vertices == VertexInput::Full)
    attributes.push_back({2, 1, VK_FORMAT_R32G32_SFLOAT, 12});
  if (d.vertices == VertexInput::Full) {
    attributes.push_back({3, 1, VK_FORMAT_R32G32B32A32_SFLOAT, 20});
    bindings.push_back({2, 12, VK_VERTEX_INPUT_RATE_VERTEX});
    attributes.push_back({4, 2, VK_FORMAT_R32G32B32_SFLOAT, 0});
  }
  VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  vi.vertexBindingDescriptionCount = uint32_t(bindings.size());
  vi.pVertexBindingDescriptions = bindings.data();
  vi.vertexAttributeDescriptionCount = uint32_t(attributes.size());
  vi.pVertexAttributeDescriptions = attributes.data();
  VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = 1;
  vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  // Static: no culling (the shadow passes, fullscreen triangles). Dynamic: per draw (drawScene).
  rs.cullMode = VK_CULL_MODE_NONE;
  rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  rs.depthBiasEnable = d.depthBias;
  rs.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  ds.depthTestEnable = d.depthTest;
  ds.depthWriteEnable = d.depthWrite;
  ds.depthCompareOp = d.depthCompare;
  std::vector<VkPipelineColorBlendAttachmentState> blends(d.colorFormats.size());
  for (auto& b : blends) {
    b.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT | VK_COLOR_COMPONENT_B_BIT |
                       VK_COLOR_COMPONENT_A_BIT;
    if (!d.blend) continue;
    b.blendEnable = VK_TRUE;  // glTF BLEND: the Porter-Duff "over" of the shaded colour with opacity alpha
    b.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA;
    b.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
    b.colorBlendOp = VK_BLEND_OP_ADD;
    b.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
    b.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
    b.alphaBlendOp = VK_BLEND_OP_ADD;
  }
  VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  cb.attachmentCount = uint32_t(blends.size());
  cb.pAttachments = blends.data();
  std::vector<VkDynamicState> dyn = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  if (d.depthBias) dyn.push_back(VK_DYNAMIC_STATE_DEPTH_BIAS);
  if (d.dynamicCulling) dyn.insert(dyn.end(), {VK_DYNAMIC_STATE_CULL_MODE, VK_DYNAMIC_STATE_FRONT_FACE});  // core 1.3
  VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dy.dynamicStateCount = uint32_t(dyn.size());
  dy.pDynamicStates = dyn.data();
  VkPipelineRenderingCreateInfo ri{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
  ri.colorAttachmentCount = uint32_t(d.colorFormats.size());
  ri.pColorAttachmentFormats = d.colorFormats.data();
  ri.depthAttachmentFormat = d.depthFormat;
  VkGraphicsPipelineCreateInfo ci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  ci.pNext = &ri;
  ci.stageCount = uint32_t(stages.size());
  ci.pStages = stages.data();
  ci.pVertexInputState = &vi;
  ci.pInputAssemblyState = &ia;
  ci.pViewportState = &vp;
  ci.pRasterizationState = &rs;
  ci.pMultisampleState = &ms;
  ci.pDepthStencilState = &ds;
  ci.pColorBlendState = &cb;
  ci.pDynamicState = &dy;
  ci.layout = d.layout;
  SE_VK_TRY(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &ci, nullptr, &out));
  return {};
}

std::string makeSampler(VkDevice device, VkFilter filter, VkSamplerAddressMode mode, bool compare, float maxLod,
                        VkSampler& out) {
  VkSamplerCreateInfo ci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  ci.magFilter = ci.minFilter = filter;
  ci.mipmapMode = filter == VK_FILTER_LINEAR ? VK_SAMPLER_MIPMAP_MODE_LINEAR : VK_SAMPLER_MIPMAP_MODE_NEAREST;
  ci.addressModeU = ci.addressModeV = ci.addressModeW = mode;
  ci.compareEnable = compare;
  ci.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
  ci.maxLod = maxLod;
  ci.borderColor = VK_BORDER_COLOR_FLOAT_OPAQUE_WHITE;
  SE_VK_TRY(vkCreateSampler(device, &ci, nullptr, &out));
  return {};
}

}  // namespace

std::string Pipelines::create(VkDevice device) {
  std::string e;
  auto check = [&](std::string r) {
    if (e.empty()) e = std::move(r);
    return e.empty();
  };
  check(makeSetLayout(device,
                      {{0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1,
                        VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT | VK_SHADER_STAGE_COMPUTE_BIT,
                        nullptr}},
                      frameSetLayout));
  check(makeSetLayout(device,
                      {samplerBinding(0), samplerBinding(1), samplerBinding(2), samplerBinding(3), samplerBinding(4)},
                      materialSetLayout));
  check(makeSetLayout(device,
                      {samplerBinding(0), samplerBinding(1), samplerBinding(2), samplerBinding(3), samplerBinding(4),
                       samplerBinding(5), bufferBinding(6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                       bufferBinding(7, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER), samplerBinding(8)},
                      lightingSetLayout));
  check(makeSetLayout(device,
                      {samplerBinding(0), samplerBinding(1), samplerBinding(2), samplerBinding(3),
                       bufferBinding(4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
                       bufferBinding(5, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER)},
                      localIrradianceSetLayout));
  check(makeSetLayout(device, {samplerBinding(0)}, tonemapSetLayout));
  check(makeSetLayout(device, {samplerBinding(0), samplerBinding(1), samplerBinding(2), samplerBinding(3)},
                      screenSetLayout));
  check(makeSetLayout(device,
                      {computeBinding(0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER),
                       computeBinding(1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER),
                       computeBinding(2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER),
                       computeBinding(kSsaoOutputBinding, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE)},
                      ssaoSetLayout));
  if (!e.empty()) return e;

  VkPushConstantRange drawRange{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(DrawConstants)};
  VkDescriptorSetLayout sets[3] = {frameSetLayout, materialSetLayout, lightingSetLayout};
  VkPipelineLayoutCreateInfo lci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  lci.setLayoutCount = 3;
  lci.pSetLayouts = sets;
  lci.pushConstantRangeCount = 1;
  lci.pPushConstantRanges = &drawRange;
  SE_VK_TRY(vkCreatePipelineLayout(device, &lci, nullptr, &sceneLayout));
  VkPushConstantRange tonemapRange{VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(float)};
  lci.setLayoutCount = 1;
  lci.pSetLayouts = &tonemapSetLayout;
  lci.pPushConstantRanges = &tonemapRange;
  SE_VK_TRY(vkCreatePipelineLayout(device, &lci, nullptr, &tonemapLayout));
  VkPushConstantRange ssaoRange{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(SsaoConstants)};
  VkDescriptorSetLayout ssaoSets[2] = {frameSetLayout, ssaoSetLayout};
  lci.setLayoutCount = 2;
  lci.pSetLayouts = ssaoSets;
  lci.pPushConstantRanges = &ssaoRange;
  SE_VK_TRY(vkCreatePipelineLayout(device, &lci, nullptr, &ssaoLayout));
  VkDescriptorSetLayout screenSets[2] = {frameSetLayout, screenSetLayout};
  lci.pSetLayouts = screenSets;
  lci.pushConstantRangeCount = 0;
  lci.pPushConstantRanges = nullptr;
  SE_VK_TRY(vkCreatePipelineLayout(device, &lci, nullptr, &screenLayout));
  VkDescriptorSetLayout irradianceSets[2] = {frameSetLayout, localIrradianceSetLayout};
  lci.pSetLayouts = irradianceSets;
  SE_VK_TRY(vkCreatePipelineLayout(device, &lci, nullptr, &localIrradianceLayout));

  VkShaderModule meshVert = VK_NULL_HANDLE, shadowVert = VK_NULL_HANDLE, shadowAlphaVert = VK_NULL_HANDLE,
                 shadowAlphaFrag = VK_NULL_HANDLE, prepassFrag = VK_NULL_HANDLE, forwardFrag = VK_NULL_HANDLE,
                 fullscreenVert = VK_NULL_HANDLE, tonemapFrag = VK_NULL_HANDLE, ssaoComp = VK_NULL_HANDLE,
                 ssaoBlurComp = VK_NULL_HANDLE, shadowVisibilityFrag = VK_NULL_HANDLE,
                 localIrradianceFrag = VK_NULL_HANDLE;
  check(makeModule(device, spirv::mesh_vert, meshVert));
  check(makeModule(device, spirv::shadow_vert, shadowVert));
  check(makeModule(device, spirv::shadow_alpha_vert, shadowAlphaVert));
  check(makeModule(device, spirv::shadow_alpha_frag, shadowAlphaFrag));
  check(makeModule(device, spirv::prepass_frag, prepassFrag));
  check(makeModule(device, spirv::forward_frag, forwardFrag));
  check(makeModule(device, spirv::fullscreen_vert, fullscreenVert));
  check(makeModule(device, spirv::tonemap_frag, tonemapFrag));
  check(makeModule(device, spirv::ssao_comp, ssaoComp));
  check(makeModule(device, spirv::ssao_blur_comp, ssaoBlurComp));
  check(makeModule(device, spirv::shadow_visibility_frag, shadowVisibilityFrag));
  check(makeModule(device, spirv::local_irradiance_frag, localIrradianceFrag));
  if (e.empty()) {
    // The shadow map keeps culling off whatever Material::doubleSided says: doubleSided is about which side
    // the camera may see, not about what blocks light. A single-sided wall, roof or leaf whose back faces the
    // sun must still shadow what is behind it (as the SDK's two-sided shadow rays see it), and a closed mesh
    // casts the same shadow with either side culled.
    PipelineDesc d;
    d.vert = shadowVert;
    d.vertices = VertexInput::Positions;
    d.depthFormat = kDepthFormat;
    d.depthTest = d.depthWrite = true;
    d.depthCompare = VK_COMPARE_OP_LESS_OR_EQUAL;
    d.depthBias = true;
    d.layout = sceneLayout;
    check(makePipeline(device, d, shadow));

    d.vert = shadowAlphaVert;
    d.frag = shadowAlphaFrag;
    d.vertices = VertexInput::PositionsUvs;
    check(makePipeline(device, d, shadowAlpha));

    d = {};
    d.vert = meshVert;
    d.frag = prepassFrag;
    d.colorFormats = {kNormalFormat, kNormalFormat, kMotionFormat};
    d.depthFormat = kDepthFormat;
    d.depthTest = d.depthWrite = true;
    d.depthCompare = VK_COMPARE_OP_LESS;
    d.dynamicCulling = true;
    d.layout = sceneLayout;
    check(makePipeline(device, d, prepass));
    d.alphaTested = true;
    check(makePipeline(device, d, prepassMasked));

    d.frag = forwardFrag;
    d.colorFormats = {kHdrFormat};
    d.depthWrite = false;
    d.depthCompare = VK_COMPARE_OP_EQUAL;  // only the surface the pre-pass kept gets shaded
    d.alphaTested = false;
    check(makePipeline(device, d, forward));
    d.alphaTested = true;
    check(makePipeline(device, d, forwardMasked));

    // In front of what the pre-pass (or the probe's opaque draws) left, never hiding what follows.
    d.depthCompare = VK_COMPARE_OP_LESS;
    d.alphaTested = false;
    d.blend = true;
    check(makePipeline(device, d, blend));
    d.blend = false;

    // Probe faces have no pre-pass: the capture does its own depth test.
    d.depthWrite = true;
    d.depthCompare = VK_COMPARE_OP_LESS;
    check(makePipeline(device, d, probeCapture));
    d.alphaTested = true;
    check(makePipeline(device, d, probeCaptureMasked));

    d = {};
    d.vert = fullscreenVert;
    d.frag = tonemapFrag;
    d.vertices = VertexInput::None;
    d.colorFormats = {kLdrFormat};
    d.layout = tonemapLayout;
    check(makePipeline(device, d, tonemap));

    d.colorFormats = {kEffectFormat};
    d.layout = screenLayout;
    d.frag = shadowVisibilityFrag;
    check(makePipeline(device, d, shadowVisibility));
    d.colorFormats = {kNormalFormat};
    d.layout = localIrradianceLayout;
    d.frag = localIrradianceFrag;
    check(makePipeline(device, d, localIrradiance));

    check(makeComputePipeline(device, ssaoComp, ssaoLayout, ssao));
    check(makeComputePipeline(device, ssaoBlurComp, ssaoLayout, ssaoBlur));
  }
  for (VkShaderModule m :
       {meshVert, shadowVert, shadowAlphaVert, shadowAlphaFrag, prepassFrag, forwardFrag, fullscreenVert, tonemapFrag,
        ssaoComp, ssaoBlurComp, shadowVisibilityFrag, localIrradianceFrag})
    if (m) vkDestroyShaderModule(device, m, nullptr);
  if (!e.empty()) return e;

  check(
      makeSampler(device, VK_FILTER_LINEAR, VK_SAMPLER_ADDRESS_MODE_REPEAT, false, VK_LOD_CLAMP_NONE, materialSampler));
  check(makeSampler(device, VK_FILTER_LINEAR, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, false, 0.0f, screenSampler));
  check(makeSampler(device, VK_FILTER_LINEAR, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_BORDER, true, 0.0f, shadowSampler));
  check(makeSampler(device, VK_FILTER_NEAREST, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, false, 0.0f, nearestSampler));
  check(makeSampler(device, VK_FILTER_LINEAR, VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, false, VK_LOD_CLAMP_NONE,
                    cubeSampler));
  return e;
}

void Pipelines::destroy(VkDevice device) {
  for (VkPipeline p : {shadow, shadowAlpha, prepass, prepassMasked, forward, forwardMasked, blend, tonemap,
                       probeCapture, probeCaptureMasked, ssao, ssaoBlur, shadowVisibility, localIrradiance})
    if (p) vkDestroyPipeline(device, p, nullptr);
  for (VkPipelineLayout l : {sceneLayout, tonemapLayout, screenLayout, ssaoLayout, localIrradianceLayout})
    if (l) vkDestroyPipelineLayout(device, l, nullptr);
  for (VkDescriptorSetLayout l : {frameSetLayout, materialSetLayout, lightingSetLayout, tonemapSetLayout,
                                  screenSetLayout, ssaoSetLayout, localIrradianceSetLayout})
    if (l) vkDestroyDescriptorSetLayout(device, l, nullptr);
  for (VkSampler s : {materialSampler, screenSampler, shadowSampler, nearestSampler, cubeSampler})
    if (s) vkDestroySampler(device, s, nullptr);
  *this = {};
}

}  // namespace sample_engine::detail
