// Descriptor-set layouts, pipeline layouts, samplers and the graphics pipelines of every pass.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <vulkan/vulkan.h>
#include <glm/glm.hpp>

#include "sample_engine/scene.h"

namespace sample_engine::detail {

// std140 mirror of FrameUniforms in shaders/common.glsl.
struct FrameUniforms {
  glm::mat4 view, proj, viewProj, invViewProj, lightViewProj;
  glm::vec4 cameraPos, sunDirection, sunRadiance, sky, viewport, shadow;
  glm::uvec4 inputs;
  glm::mat4 invProj;
  glm::vec4 probe;  // x: 1 = sample the reflection probe, y: its last mip level
  // x: KHR lights in the light buffer (0 = none: local lights off, the probe capture), y: 1 = external E bound
  glm::uvec4 localLights;
  // Last frame's camera-relative position -> clip, rebased to this frame's eye (the pre-pass's motion vectors).
  glm::mat4 previousViewProj;
};

// Mirror of DrawConstants in shaders/common.glsl (push constants, vertex + fragment; std430 layout).
struct DrawConstants {
  glm::mat4 model;  // instance-local -> camera-relative, per draw
  glm::vec4 baseColorFactor;
  glm::vec4 material;  // x: metallic, y: perceptual roughness, z: normal scale, w: occlusion strength (0 = none)
  glm::vec3 emissive;
  uint32_t alphaMode;  // Material::alphaMode (SE_ALPHA_* in common.glsl)
  float alphaCutoff;   // Material::alphaCutoff
  uint32_t instance;   // Scene::instances index, per draw (seeds the hashed shadow test of BLEND draws)
  // Device address of last frame's model matrices (one glm::mat4 per instance, rebased to this frame's eye); 0 = none
  // (the instance is taken as still: the probe capture, a device without bufferDeviceAddress).
  uint64_t previousModels;
};
static_assert(offsetof(DrawConstants, baseColorFactor) == 64);
static_assert(offsetof(DrawConstants, material) == 80);
static_assert(offsetof(DrawConstants, emissive) == 96);
static_assert(offsetof(DrawConstants, alphaMode) == 108);
static_assert(offsetof(DrawConstants, alphaCutoff) == 112);
static_assert(offsetof(DrawConstants, instance) == 116);
static_assert(offsetof(DrawConstants, previousModels) == 120);
static_assert(sizeof(DrawConstants) == 128);
static_assert(sizeof(DrawConstants) <= 128, "Vulkan guarantees 128 bytes of push constants");
// SE_ALPHA_OPAQUE / MASK / BLEND in shaders/common.glsl.
static_assert(uint32_t(AlphaMode::Opaque) == 0 && uint32_t(AlphaMode::Mask) == 1 && uint32_t(AlphaMode::Blend) == 2);

inline constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
inline constexpr VkFormat kNormalFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
// Motion vectors in pixels: 16-bit float keeps 1/64 px up to 512 px of motion (the reprojection needs far less).
inline constexpr VkFormat kMotionFormat = VK_FORMAT_R16G16_SFLOAT;
inline constexpr VkFormat kHdrFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
inline constexpr VkFormat kLdrFormat = VK_FORMAT_R8G8B8A8_SRGB;
// Single-channel effect images (SSAO, shadow visibility): 16-bit float keeps smooth gradients for readback.
inline constexpr VkFormat kEffectFormat = VK_FORMAT_R16_SFLOAT;
inline constexpr uint32_t kScreenSetBindings = 4;    // combined image samplers of a fullscreen pass (set 1)
inline constexpr uint32_t kMaterialSetBindings = 5;  // base colour, metallic-roughness, normal, emissive, occlusion
// Lighting set (set 2 of the scene passes): 0 sun shadow map, 1 sun visibility, 2 AO, 3 reflection, 4 probe cube,
// 5 local shadow maps (2D array, comparison), 6 KHR light buffer (storage), 7 local shadow views (uniform),
// 8 external local-light irradiance.
inline constexpr uint32_t kLightingSetBindings = 9;
inline constexpr uint32_t kLightingSetSamplers = 7;
inline constexpr uint32_t kLightingLocalLightBinding = 5;  // the three bindings of shaders/local_lights.glsl
// The local-irradiance pass's set 1: 0 depth, 1 shading normal, 2 geometric normal, 3-5 local_lights.glsl.
inline constexpr uint32_t kLocalIrradianceLocalLightBinding = 3;

// The SSAO compute passes' set 1 (shaders/ssao_inputs.glsl): 0 depth, 1 geometric normal, 2 raw AO (the blur's
// input) as combined image samplers, 3 the output (storage image, kEffectFormat).
inline constexpr uint32_t kSsaoSetSamplers = 3;
inline constexpr uint32_t kSsaoOutputBinding = 3;

// Mirror of SsaoConstants in shaders/ssao_inputs.glsl (push constants of ssao.comp and ssao_blur.comp).
struct SsaoConstants {
  float radius;           // SsaoSettings::radius, world units
  float bias;             // SsaoSettings::bias, world units along the normal
  float power;            // SsaoSettings::power
  uint32_t sliceCount;    // from SsaoSettings::kernelSize (see there)
  uint32_t stepsPerSide;  // from SsaoSettings::kernelSize
};
static_assert(offsetof(SsaoConstants, sliceCount) == 12);
static_assert(offsetof(SsaoConstants, stepsPerSide) == 16);
static_assert(sizeof(SsaoConstants) == 20);

struct Pipelines {
  // Scene passes: set 0 frame uniforms; set 1 material textures; set 2 lighting inputs (shadow map,
  // visibility / AO / reflection images, reflection-probe cube).
  // Fullscreen shadow-visibility pass: set 0 frame uniforms; set 1 up to kScreenSetBindings sampled images.
  // SSAO compute passes: set 0 frame uniforms; set 1 ssaoSetLayout; push constants SsaoConstants.
  VkDescriptorSetLayout frameSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout materialSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout lightingSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout tonemapSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout screenSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout ssaoSetLayout = VK_NULL_HANDLE;
  VkDescriptorSetLayout localIrradianceSetLayout = VK_NULL_HANDLE;
  VkPipelineLayout sceneLayout = VK_NULL_HANDLE;
  VkPipelineLayout tonemapLayout = VK_NULL_HANDLE;
  VkPipelineLayout screenLayout = VK_NULL_HANDLE;
  VkPipelineLayout ssaoLayout = VK_NULL_HANDLE;
  VkPipelineLayout localIrradianceLayout = VK_NULL_HANDLE;  // set 0 frame uniforms, set 1 localIrradianceSetLayout
  // Scene pipelines come in pairs: OPAQUE draws, and MASK draws (*Masked: the alpha test's discard, which the
  // opaque ones lack so that their depth writes keep early depth tests). BLEND draws use `blend` (and the
  // shadow map's alpha-tested variant). Camera passes take cull mode and front face per draw (dynamic state,
  // Material::doubleSided and the model matrix's handedness); the shadow passes never cull.
  VkPipeline shadow = VK_NULL_HANDLE;       // positions only, no fragment shader: OPAQUE draws
  VkPipeline shadowAlpha = VK_NULL_HANDLE;  // positions + UVs, alpha test (MASK: cutoff, BLEND: hashed)
  VkPipeline prepass = VK_NULL_HANDLE;
  VkPipeline prepassMasked = VK_NULL_HANDLE;
  VkPipeline forward = VK_NULL_HANDLE;  // depth EQUAL against the pre-pass
  VkPipeline forwardMasked = VK_NULL_HANDLE;
  // BLEND draws, after the opaque lighting, in the main view and the probe capture: forward shading blended
  // (src alpha, one minus src alpha) into the HDR target, depth LESS without writes.
  VkPipeline blend = VK_NULL_HANDLE;
  VkPipeline tonemap = VK_NULL_HANDLE;
  VkPipeline probeCapture = VK_NULL_HANDLE;  // forward shading with its own depth test (LESS, writes)
  VkPipeline probeCaptureMasked = VK_NULL_HANDLE;
  VkPipeline ssao = VK_NULL_HANDLE;      // compute: GTAO horizon search (shaders/ssao.comp)
  VkPipeline ssaoBlur = VK_NULL_HANDLE;  // compute: its depth-aware 4x4 blur (shaders/ssao_blur.comp)
  VkPipeline shadowVisibility = VK_NULL_HANDLE;
  VkPipeline localIrradiance = VK_NULL_HANDLE;  // fullscreen, RGBA16F: the engine's KHR-light irradiance E
  VkSampler materialSampler = VK_NULL_HANDLE;   // trilinear, repeat
  VkSampler screenSampler = VK_NULL_HANDLE;     // bilinear, clamp: external screen-space inputs
  VkSampler shadowSampler = VK_NULL_HANDLE;     // comparison LESS_OR_EQUAL, bilinear PCF
  VkSampler nearestSampler = VK_NULL_HANDLE;
  VkSampler cubeSampler = VK_NULL_HANDLE;  // trilinear, clamp: reflection probe

  std::string create(VkDevice device);
  void destroy(VkDevice device);
};

}  // namespace sample_engine::detail
