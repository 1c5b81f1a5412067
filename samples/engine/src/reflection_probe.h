// The engine's static reflection probe: a small mip-mapped cubemap captured with the forward shading from
// one point, the raster fallback for the ray-traced reflections an add-on can supply instead.
#pragma once

#include <array>
#include <string>

#include "gpu_memory.h"
#include "gpu_scene.h"
#include "pipelines.h"
#include "render_utils.h"
#include "sample_engine/engine.h"
#include "vk_context.h"

namespace sample_engine::detail {

// Everything a capture depends on: when it changes, the probe is captured again.
struct ProbeKey {
  uint64_t sceneVersion = 0;
  uint32_t resolution = 0;
  glm::vec3 position{0.0f};  // world space; the capture rebases the scene to it
  glm::vec4 sunDirection{0.0f}, sunRadiance{0.0f}, sky{0.0f}, shadow{0.0f};
  glm::mat4 lightViewProj{0.0f};  // the shadow map's light view-projection for positions relative to `position`
  float depthBiasConstant = 0.0f, depthBiasSlope = 0.0f;
  bool operator==(const ProbeKey&) const = default;
};

class ReflectionProbe {
 public:
  std::string create(Gpu& gpu, const VulkanContext& ctx, const Pipelines& pipelines);
  void destroy(Gpu& gpu);

  // Probe position for `settings`: the explicit one, else the bounds centre raised to heightAboveGround.
  static glm::vec3 positionFor(const ReflectionProbeSettings& settings, const Bounds& bounds);
  static uint32_t clampResolution(uint32_t resolution);

  // True when the probe is missing or was captured for different inputs.
  bool needsCapture(const ProbeKey& key) const { return !captured_ || key != key_; }
  // Makes sure the cube has `resolution` texels per face. Recreating it waits for the GPU (the frames in
  // flight may sample the old cube), like a shadow-map resize.
  std::string prepare(uint32_t resolution);

  // Records the capture of the six faces and the mip chain into `cmd`, using frame slot `slot`'s uniform
  // buffer and descriptor sets (free once that slot's previous frame completed). `base` supplies the sun,
  // sky and shadow-map settings of the frame, `key` the position and the probe-relative light matrix (the
  // faces are rendered relative to the probe position); `shadowMap` must be in SHADER_READ_ONLY_OPTIMAL.
  // Binds set 0 and set 2 of Pipelines::sceneLayout: the caller rebinds its own afterwards.
  // `localLights`: bound for the lighting set's layout only; the capture draws no KHR lights (its uniforms
  // say 0 lights: their buffer holds camera-relative positions).
  void recordCapture(VkCommandBuffer cmd, uint32_t slot, const FrameUniforms& base, const ProbeKey& key,
                     const GpuScene* scene, VkImageView shadowMap, const DefaultImages& defaults,
                     const LocalLightBindings& localLights);

  bool captured() const { return captured_; }
  // The captured cube (SHADER_READ_ONLY_OPTIMAL after a capture), or a 1x1 black cube bound when no probe
  // is in use.
  VkImageView view() const { return captured_ ? cube_.view : fallback_.view; }
  VkImageView fallbackView() const { return fallback_.view; }
  float maxLod() const { return captured_ ? float(cube_.mipLevels - 1) : 0.0f; }

 private:
  struct SlotResources {
    Buffer uniforms;  // six FrameUniforms, one per face, `uniformStride_` apart
    std::array<VkDescriptorSet, 6> faceSets{};
    VkDescriptorSet lightingSet = VK_NULL_HANDLE;
  };

  void destroyCube();

  Gpu* gpu_ = nullptr;
  const Pipelines* pipelines_ = nullptr;
  VkDevice device_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDeviceSize uniformStride_ = 0;
  std::array<SlotResources, kFramesInFlight> slots_;
  Image fallback_;                          // 1x1 black cube
  Image cube_;                              // RGBA16F cube with mips
  std::array<VkImageView, 6> faceViews_{};  // mip 0 of each face, render targets
  Image depth_;                             // one face's depth, reused by every face
  bool captured_ = false;
  ProbeKey key_;
};

}  // namespace sample_engine::detail
