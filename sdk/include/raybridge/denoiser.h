// Denoising for single-channel ray-traced signals (shadow visibility, AO): temporal accumulation with
// reprojection (camera motion, or the engine's motion vectors when GBufferDesc::motionVectors is given),
// followed by an edge-aware a-trous spatial filter guided by depth and normals. Each signal needs its own
// Denoiser (it keeps that signal's history). The raw input is left untouched, so raw and denoised are both
// available.
//
// Lifetime: destroying it is safe while frames that recorded it are in flight: its pipelines, history and
// output images and measurement objects are handed to the Context's deferred release (see context.h) and
// freed once those frames are done. Destroy it before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/context.h>
#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>

#include <memory>

namespace rb {

struct DenoiseSettings {
  bool disableTemporal = false;    // false = accumulate over frames
  bool disableSpatial = false;     // false = run the a-trous filter
  uint32_t spatialIterations = 0;  // 0 = 2 (steps 1 and 2: a 13x13 footprint; 3 over-blurs 4-ray AO)
  uint32_t maxHistoryFrames = 0;   // 0 = 32: the running mean forgets more slowly than this
  float depthSigma = 0.0f;         // 0 = 0.005: plane-distance tolerance relative to view distance, per step
  float normalPower = 0.0f;        // 0 = 32: exponent of the normal similarity weight
  // Rays per pixel behind the signal, when it is a fraction of binary rays (shadow visibility, binary AO):
  // the spatial filter then knows the noise exactly and keeps every edge that is not noise. 0 = unknown:
  // the noise is estimated from the 3x3 neighbourhood, which also blurs thin noise-free features.
  uint32_t raysPerPixel = 0;
};

// Owned by the denoiser, left in SHADER_READ_ONLY_OPTIMAL after record().
struct DenoiseOutputs {
  VkImage denoised = VK_NULL_HANDLE;  // R16_SFLOAT
  VkImageView denoisedView = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
};

class Denoiser {
 public:
  static Result<std::unique_ptr<Denoiser>> create(Context& context);
  // Retires its Vulkan objects to the context, without waiting: the images of outputs() stay valid for
  // the frames already recorded.
  ~Denoiser();

  // `signal`: an R16/R32 float image view with the noisy value in .r, in SHADER_READ_ONLY_OPTIMAL (the
  // outputs of ShadowPass and AoPass are). The G-buffer is the one the signal was traced from.
  Status record(VkCommandBuffer cmd, const GBufferDesc& gbuffer, VkImageView signal,
                const DenoiseSettings& settings = {});
  // Forget the history (after a camera cut or a scene change).
  void resetHistory();
  const DenoiseOutputs& outputs() const;
  PassStats stats() const;  // GPU time (rays are 0: the denoiser traces none)

  struct Impl;

 private:
  explicit Denoiser(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
