// Engine internals shared by engine.cpp (setup, scene, readback), frame_recorder.cpp (the frame) and
// swapchain.cpp (presentation).
#pragma once

#include <array>
#include <optional>

#include "gpu_memory.h"
#include "gpu_scene.h"
#include "pipelines.h"
#include "sample_engine/engine.h"
#include "vk_context.h"

namespace sample_engine {

// Timestamp slots written into each frame's query pool.
enum TimestampSlot : uint32_t {
  kTsStart,
  kTsShadowEnd,
  kTsPrepassEnd,
  kTsHookEnd,
  kTsLightingEnd,
  kTsTonemapEnd,
  kTsCount
};

struct FrameResources {
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;           // signaled when the frame's GPU work is done
  VkSemaphore imageAcquired = VK_NULL_HANDLE;
  detail::Buffer uniforms;                  // FrameUniforms, host visible
  VkDescriptorSet frameSet = VK_NULL_HANDLE;
  VkDescriptorSet lightingSet = VK_NULL_HANDLE;
  VkDescriptorSet tonemapSet = VK_NULL_HANDLE;
  VkQueryPool timestamps = VK_NULL_HANDLE;
  bool timingsPending = false;              // submitted with timestamps, not read back yet
  uint64_t frameNumber = 0;
};

// Images rewritten every frame. One set is enough for two frames in flight: the frames run in
// submission order on one queue and each frame's first barrier waits for the previous frame's use.
struct RenderTargets {
  detail::Image depth, normalRoughness, geometricNormal, hdr, ldr;
  detail::Image shadowMap;
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
  bool sceneLoaded = false;
  VkDescriptorPool framePool = VK_NULL_HANDLE;
  std::array<FrameResources, kFramesInFlight> frames;
  RenderTargets targets;
  Swapchain swapchain;
  PrepassHook hook;
  uint32_t currentFrame = 0;
  uint64_t frameCounter = 0;
  bool frameRendered = false;  // targets hold a finished frame (for readback)
  std::optional<uint32_t> lastSubmittedSlot;
  PassTimings timings;
  uint64_t timingsFrameNumber = 0;

  ~Impl();
  std::string init(const EngineConfig& config);
  std::string createTargets(VkExtent2D extent);
  std::string createShadowMap(uint32_t size);
  void destroyTargets();
  void collectTimings(FrameResources& frame);
  std::string waitFrame(FrameResources& frame);

  // frame_recorder.cpp
  std::string renderFrame(const FrameParams& params);
  void recordFrame(FrameResources& frame, const FrameParams& params, const detail::FrameUniforms& uniforms,
                   std::optional<uint32_t> swapchainImage);

  // swapchain.cpp
  std::string createSwapchain(uint32_t width, uint32_t height);
  void destroySwapchain(bool destroySurface);
};

}  // namespace sample_engine
