// Engine internals shared by engine.cpp (setup, scene, readback), frame_recorder.cpp (the frame),
// effect_passes.cpp (SSAO, shadow visibility) and swapchain.cpp (presentation).
#pragma once

#include <array>
#include <optional>

#include "deformer.h"
#include "gpu_memory.h"
#include "gpu_scene.h"
#include "local_lights.h"
#include "pipelines.h"
#include "reflection_probe.h"
#include "render_utils.h"
#include "sample_engine/engine.h"
#include "vk_context.h"

namespace sample_engine {

// Timestamp slots written into each frame's query pool.
enum TimestampSlot : uint32_t {
  kTsStart,
  kTsShadowEnd,
  kTsProbeEnd,
  kTsPrepassEnd,
  kTsSsaoEnd,
  kTsShadowVisibilityEnd,
  kTsHookEnd,
  kTsLocalShadowEnd,
  kTsLocalIrradianceEnd,
  kTsLightingEnd,
  kTsTonemapEnd,
  kTsCount
};

struct FrameResources {
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;  // signaled when the frame's GPU work is done
  VkSemaphore imageAcquired = VK_NULL_HANDLE;
  detail::Buffer uniforms;  // FrameUniforms, host visible
  // Last frame's model matrices rebased to this frame's eye (DrawConstants::previousModels), host visible, one
  // glm::mat4 per scene instance; grown on demand.
  detail::Buffer previousModels;
  VkDescriptorSet frameSet = VK_NULL_HANDLE;
  VkDescriptorSet lightingSet = VK_NULL_HANDLE;
  VkDescriptorSet tonemapSet = VK_NULL_HANDLE;
  VkDescriptorSet ssaoSet = VK_NULL_HANDLE;  // SSAO compute inputs and output (Pipelines::ssaoSetLayout)
  VkDescriptorSet ssaoBlurSet = VK_NULL_HANDLE;
  VkDescriptorSet shadowVisibilitySet = VK_NULL_HANDLE;  // Pipelines::screenSetLayout
  // KHR lights (local_lights.cpp): the light buffer and shadow views the lighting reads, one FrameUniforms copy
  // per local shadow view (its lightViewProj replaced) and their sets, the irradiance output's inputs.
  detail::Buffer localLightBuffer, localShadowBuffer, shadowViewUniforms;
  std::array<VkDescriptorSet, detail::kMaxLocalShadowViews> shadowViewSets{};
  VkDescriptorSet localIrradianceSet = VK_NULL_HANDLE;
  VkQueryPool timestamps = VK_NULL_HANDLE;
  bool timingsPending = false;  // submitted with timestamps, not read back yet
  bool inFlight = false;        // submitted: the fence signals when it is done (a failed submit leaves it unsignaled)
  bool probeCaptured = false;   // this frame recorded a probe capture
  uint64_t frameNumber = 0;
};

// Images rewritten every frame. One set is enough for two frames in flight: the frames run in
// submission order on one queue and each frame's first barrier waits for the previous frame's use.
struct RenderTargets {
  detail::Image depth, normalRoughness, geometricNormal, motionVectors, hdr, ldr;
  // The sun's depth map, targets.shadowMapSize texels square; a 1x1 placeholder (never rendered, only bound)
  // while the shadow map is disabled.
  detail::Image shadowMap;
  // Effect images (kEffectFormat, left in SHADER_READ_ONLY_OPTIMAL), created on first use at this extent.
  detail::Image ssaoRaw, ssao, shadowVisibility;
  // KHR lights: 6 depth layers per shadowed light (a 1x1 one-layer placeholder without any), one view per layer
  // for rendering; kept in SHADER_READ_ONLY_OPTIMAL between passes. The irradiance output (RGBA16F).
  detail::Image localShadowMaps;
  std::vector<VkImageView> localShadowLayerViews;
  uint32_t localShadowMapSize = 0, localShadowLayers = 0;
  detail::Image localIrradiance;
  VkExtent2D extent{};
  uint32_t shadowMapSize = 0;
};

struct Swapchain {
  VkSurfaceKHR surface = VK_NULL_HANDLE;
  VkSwapchainKHR swapchain = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{};
  std::vector<VkImage> images;
  std::vector<VkSemaphore> renderFinished;  // per swapchain image: presentation waits on it
};

struct Engine::Impl {
  detail::VulkanContext ctx;
  detail::Gpu gpu;
  detail::Pipelines pipelines;
  detail::DefaultImages defaults;
  detail::GpuScene scene;
  ScenePose pose;                                  // the loaded scene's, evaluated every frame
  detail::Deformer deformer;                       // skinning / morphing of the loaded scene's deforming instances
  std::vector<VkSemaphoreSubmitInfo> submitWaits;  // the hook's additions to this frame's main submission
  std::vector<VkSemaphoreSubmitInfo> mainWaits;    // reused: all waits of the main submission
  bool sceneLoaded = false;
  // What the last rendered frame drew, for this frame's motion vectors: its instance transforms and camera (eye,
  // rotation-only view, projection). Empty / unset after loadScene() and before the first frame: no motion.
  std::vector<glm::mat4> previousTransforms;
  bool hasPreviousCamera = false;
  glm::dvec3 previousEye{0.0};
  glm::mat4 previousView{1.0f}, previousProj{1.0f};
  uint64_t sceneVersion = 0;  // bumped by loadScene (the reflection probe recaptures)
  detail::ReflectionProbe probe;
  VkDescriptorPool framePool = VK_NULL_HANDLE;
  std::array<FrameResources, kFramesInFlight> frames;
  RenderTargets targets;
  Swapchain swapchain;
  PrepassHook hook;
  OverlayHook overlayHook;
  VkRenderPass overlayRenderPass = VK_NULL_HANDLE;    // created with the first overlay hook (swapchain.cpp)
  VkFramebuffer overlayFramebuffer = VK_NULL_HANDLE;  // targets.ldr in overlayRenderPass; dies with the targets
  uint32_t currentFrame = 0;
  uint64_t frameCounter = 0;
  bool frameRendered = false;  // targets hold a finished frame (for readback)
  bool ssaoRendered = false;   // the last submitted frame wrote targets.ssao
  bool shadowVisibilityRendered = false;
  std::optional<uint32_t> lastSubmittedSlot;
  PassTimings timings;
  ShadowMapStats shadowStats;  // of the last submitted frame
  // KHR lights: the last frame's placement (rest pose after loadScene()) and what it drew.
  std::vector<FrameLight> frameLights;
  LocalShadowStats localShadowStats;
  bool localIrradianceRendered = false;  // the last submitted frame wrote targets.localIrradiance
  bool prepassRendered = false;          // the last submitted frame drew the pre-pass (no external colour)
  uint64_t timingsFrameNumber = 0;
  // A submit or a fence wait returned VK_ERROR_DEVICE_LOST: every later frame, wait and readback fails at once.
  bool deviceLost = false;

  ~Impl();
  std::string init(const EngineConfig& config);
  std::string createTargets(VkExtent2D extent);
  std::string createShadowMap(uint32_t size);
  void destroyTargets();
  void collectTimings(FrameResources& frame);
  std::string waitFrame(FrameResources& frame);
  // The error of a failed submit or wait (`what` names the call); remembers a lost device.
  std::string gpuFailure(const char* what, VkResult r);
  std::string lostDeviceError(const char* call) const;

  // frame_recorder.cpp
  std::string renderFrame(const FrameParams& params);
  // Fills frame.previousModels with last frame's instance transforms rebased to `eye` (this frame's where an
  // instance has none: the first frame, a new scene) and points scene.previousModels at it.
  std::string writePreviousModels(FrameResources& frame, const glm::dvec3& eye);
  void recordFrame(FrameResources& frame, const FrameParams& params, const detail::FrameUniforms& uniforms,
                   std::optional<uint32_t> swapchainImage, bool captureProbe, const detail::ProbeKey& probeKey);

  // effect_passes.cpp: create the effect images a frame needs, then record the passes (each leaves its
  // output in SHADER_READ_ONLY_OPTIMAL, visible to fragment shaders; the SSAO images also to compute).
  std::string ensureEffectImages(const FrameParams& params);
  void recordSsao(FrameResources& frame, const SsaoSettings& settings);
  void recordShadowVisibility(FrameResources& frame);

  // local_lights.cpp: per-frame light buffers and shadow-view sets (init), the local shadow maps (recreated
  // when the settings change, waiting for the GPU), and after the hook: the light buffers, the shadow views of
  // the strongest lights and, on request, the irradiance output (writes kTsLocalShadowEnd/IrradianceEnd).
  VkDescriptorPool localLightPool = VK_NULL_HANDLE;
  VkDeviceSize shadowViewStride = 0;
  std::string createLocalLights();
  void destroyLocalLights();
  void destroyLocalShadowMaps();
  std::string prepareLocalShadowMaps(const LocalLightSettings& settings);
  detail::LocalLightBindings localLightBindings(const FrameResources& frame) const;
  void recordLocalLights(FrameResources& frame, const FrameParams& params, const detail::FrameUniforms& uniforms,
                         const LightingInputs& inputs);

  // swapchain.cpp
  std::string createSwapchain(uint32_t width, uint32_t height);
  void destroySwapchain(bool destroySurface);
  // swapchain.cpp: the overlay hook's render pass / framebuffer, and its call after the tonemap pass.
  std::string prepareOverlay();
  void recordOverlay(FrameResources& frame, std::optional<uint32_t> swapchainImage);
  void destroyOverlayFramebuffer();
  void destroyOverlay();
};

}  // namespace sample_engine
