// Descriptor-set layouts, pipeline layouts, samplers and the graphics pipelines of every pass.
#pragma once

#include <string>

#include <vulkan/vulkan.h>
#include <glm/glm.hpp>

namespace sample_engine::detail {

// std140 mirror of FrameUniforms in shaders/common.glsl.
struct FrameUniforms {
  glm::mat4 view, proj, viewProj, invViewProj, lightViewProj;
  glm::vec4 cameraPos, sunDirection, sunRadiance, sky, viewport, shadow;
  glm::uvec4 inputs;
  glm::mat4 invProj;
  glm::vec4 probe;  // x: 1 = sample the reflection probe, y: its last mip level
};

// Mirror of DrawConstants in shaders/common.glsl (push constants, vertex + fragment).
struct DrawConstants {
  glm::mat4 model;
  glm::vec4 baseColorFactor;
  glm::vec4 material;
  glm::vec4 emissive;
};

inline constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
inline constexpr VkFormat kNormalFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
inline constexpr VkFormat kHdrFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
inline constexpr VkFormat kLdrFormat = VK_FORMAT_R8G8B8A8_SRGB;
// Single-channel effect images (SSAO, shadow visibility): 16-bit float keeps smooth gradients for readback.
inline constexpr VkFormat kEffectFormat = VK_FORMAT_R16_SFLOAT;
inline constexpr uint32_t kScreenSetBindings = 4;  // combined image samplers of a fullscreen pass (set 1)
inline constexpr uint32_t kLightingSetBindings = 5;

// Mirror of SsaoConstants in shaders/ssao.frag and ssao_blur.frag (push constants of the fullscreen passes).
struct SsaoConstants {
  float radius;
  float bias;
  float power;
  uint32_t kernelSize;
};

struct Pipelines {
  // Scene passes: set 0 frame uniforms; set 1 material textures; set 2 lighting inputs (shadow map,
  // visibility / AO / reflection images, reflection-probe cube).
  // Fullscreen effect passes (SSAO, its blur, shadow visibility): set 0 frame uniforms; set 1 up to
  // kScreenSetBindings sampled images; push constants SsaoConstants.
  VkDescriptorSetLayout frameSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout materialSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout lightingSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout tonemapSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout screenSetLayout = VK_NULL_HANDLE;
  VkPipelineLayout sceneLayout = VK_NULL_HANDLE;
  VkPipelineLayout tonemapLayout = VK_NULL_HANDLE;
  VkPipelineLayout screenLayout = VK_NULL_HANDLE;
  VkPipeline shadow = VK_NULL_HANDLE;
  VkPipeline prepass = VK_NULL_HANDLE;
  VkPipeline forward = VK_NULL_HANDLE;
  VkPipeline tonemap = VK_NULL_HANDLE;
  VkPipeline probeCapture = VK_NULL_HANDLE;  // forward shading with its own depth test (LESS, writes)
  VkPipeline ssao = VK_NULL_HANDLE;
  VkPipeline ssaoBlur = VK_NULL_HANDLE;
  VkPipeline shadowVisibility = VK_NULL_HANDLE;
  VkSampler materialSampler = VK_NULL_HANDLE;  // trilinear, repeat
  VkSampler screenSampler = VK_NULL_HANDLE;    // bilinear, clamp: external screen-space inputs
  VkSampler shadowSampler = VK_NULL_HANDLE;    // comparison LESS_OR_EQUAL, bilinear PCF
  VkSampler nearestSampler = VK_NULL_HANDLE;
  VkSampler cubeSampler = VK_NULL_HANDLE;  // trilinear, clamp: reflection probe

  std::string create(VkDevice device);
  void destroy(VkDevice device);
};

}  // namespace sample_engine::detail
