// Descriptor-set layouts, pipeline layouts, samplers and the graphics pipelines of every pass.
#pragma once

#include <string>

#include <glm/glm.hpp>
#include <vulkan/vulkan.h>

namespace sample_engine::detail {

// std140 mirror of FrameUniforms in shaders/common.glsl.
struct FrameUniforms {
  glm::mat4 view, proj, viewProj, invViewProj, lightViewProj;
  glm::vec4 cameraPos, sunDirection, sunRadiance, sky, viewport, shadow;
  glm::uvec4 inputs;
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

struct Pipelines {
  // set 0: frame uniforms; set 1: material textures; set 2: lighting inputs (shadow map + external images)
  VkDescriptorSetLayout frameSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout materialSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout lightingSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout tonemapSetLayout = VK_NULL_HANDLE;
  VkPipelineLayout sceneLayout = VK_NULL_HANDLE;
  VkPipelineLayout tonemapLayout = VK_NULL_HANDLE;
  VkPipeline shadow = VK_NULL_HANDLE;
  VkPipeline prepass = VK_NULL_HANDLE;
  VkPipeline forward = VK_NULL_HANDLE;
  VkPipeline tonemap = VK_NULL_HANDLE;
  VkSampler materialSampler = VK_NULL_HANDLE;  // trilinear, repeat
  VkSampler screenSampler = VK_NULL_HANDLE;    // bilinear, clamp: external screen-space inputs
  VkSampler shadowSampler = VK_NULL_HANDLE;    // comparison LESS_OR_EQUAL, bilinear PCF
  VkSampler nearestSampler = VK_NULL_HANDLE;

  std::string create(VkDevice device);
  void destroy(VkDevice device);
};

}  // namespace sample_engine::detail
